//! Copying a device buffer back to the host, blocking until it arrives.

use super::context::{GpuContext, GpuError};

pub fn read_buffer(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    read_buffer_range(ctx, buffer, 0, size)
}

/// `size` bytes of `buffer` from `offset` (both multiples of 4, as copies require).
pub fn read_buffer_range(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    map_and_read(ctx, &staging)
}

/// Maps a MAP_READ buffer after the queued work that fills it, and copies it out.
pub fn map_and_read(ctx: &GpuContext, staging: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    const DURING: &str = "reading results back";
    ctx.check_lost(DURING)?;
    // A wait or map that fails on a lost device says so, rather than how it failed.
    let runtime = |message: String| match ctx.check_lost(DURING) {
        Err(lost) => lost,
        Ok(()) => GpuError::Runtime {
            during: DURING.into(),
            message,
        },
    };
    let (tx, rx) = std::sync::mpsc::channel();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        // The receiver outlives the wait below; a send error cannot happen.
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| runtime(e.to_string()))?;
    rx.recv()
        .map_err(|e| runtime(e.to_string()))?
        .map_err(|e| runtime(e.to_string()))?;
    let data = {
        let view = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| runtime(e.to_string()))?;
        view.to_vec()
    };
    staging.unmap();
    // A lost device may complete the map with whatever the buffer held.
    ctx.check_lost(DURING)?;
    Ok(data)
}
