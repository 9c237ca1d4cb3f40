//! The wgpu device the renderer runs on: adapter choice, device creation, and the
//! adapter list `kiln info` prints.

use std::sync::Arc;

use thiserror::Error;

use crate::shader::bindings::TexelReads;

/// Which graphics API to run compute on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl Backend {
    fn backends(self) -> wgpu::Backends {
        match self {
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
            Backend::Metal => wgpu::Backends::METAL,
            Backend::Dx12 => wgpu::Backends::DX12,
        }
    }
}

#[derive(Debug, Error)]
pub enum GpuError {
    #[error(
        "no usable GPU adapter{backend}: {reason}. On Linux without a GPU, install Mesa's software Vulkan driver (Debian: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter { backend: String, reason: String },
    #[error("could not open a device on {adapter}: {reason}")]
    Device { adapter: String, reason: String },
    #[error("the GPU reported an error during {during}: {message}")]
    Runtime { during: String, message: String },
    #[error("the GPU device ({adapter}) was lost during {during}: {reason}")]
    DeviceLost {
        adapter: String,
        during: String,
        reason: String,
    },
}

/// An adapter, its device and queue. Shared (`Arc`) by every renderer and probe of a
/// process, so that one device (and its pipeline cache) serves them all.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Compiled pipelines by kernel source and entry point (`KernelSource::create_pipeline`):
    /// a scene rendered again with the same features and materials, or a restarted
    /// render, skips naga and the driver's compile.
    pub(crate) pipelines: std::sync::Mutex<PipelineCache<PipelineKey, wgpu::ComputePipeline>>,
    /// Pipelines compiled on this context (cache misses), so the cache can be checked.
    pub(crate) pipelines_compiled: std::sync::atomic::AtomicUsize,
    /// Why the device was lost, once the driver says it was (a crash, a reset after a
    /// dispatch ran too long, `destroy`): every later wait and read fails naming it.
    lost: Arc<std::sync::Mutex<Option<String>>>,
    /// Where a renderer's kernel is compiled first when this context has not compiled
    /// it (see [`GpuContext::rehearse_compiles_on`]).
    rehearsal: std::sync::OnceLock<Arc<GpuContext>>,
    /// The device can bind texel tables as read-only storage textures
    /// ([`TexelReads::Storage`]); the tables are created so that both ways can read them.
    pub storage_texels: bool,
    /// How kernels on this device read texel tables unless a render says otherwise
    /// ([`RenderSettings::texel_reads`](super::RenderSettings::texel_reads)).
    pub texel_reads: TexelReads,
}

/// The optional device features Kiln asks of `adapter`: adapter-specific format
/// features where it has them, for read-only storage textures ([`TexelReads::Storage`]).
pub fn device_features(adapter: &wgpu::Adapter) -> wgpu::Features {
    adapter.features() & wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
}

/// Whether `device` on `adapter` can read rgba32uint storage textures, and how its kernels
/// read texel tables: as storage textures on a software rasteriser that can (llvmpipe: 1.5×
/// faster, docs/BENCHMARKS.md), sampled elsewhere (not measured on a GPU, where both go
/// through the same texture units). wgpu's GL backend on llvmpipe offers read-only storage
/// textures but reads zeros from them (`tests/cli_flags.rs` renders through both APIs and
/// compares), so GL reads texel tables sampled.
fn texel_reads_for(adapter: &wgpu::Adapter, device: &wgpu::Device) -> (bool, TexelReads) {
    let info = adapter.get_info();
    let format = adapter.get_texture_format_features(wgpu::TextureFormat::Rgba32Uint);
    let storage = info.backend != wgpu::Backend::Gl
        && device
            .features()
            .contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
        && format
            .allowed_usages
            .contains(wgpu::TextureUsages::STORAGE_BINDING)
        && format
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::STORAGE_READ_ONLY);
    let reads = if storage && info.device_type == wgpu::DeviceType::Cpu {
        TexelReads::Storage
    } else {
        TexelReads::Sampled
    };
    (storage, reads)
}

/// Records in the returned slot why `device` is lost, when it is.
fn watch_for_loss(device: &wgpu::Device) -> Arc<std::sync::Mutex<Option<String>>> {
    let lost = Arc::new(std::sync::Mutex::new(None));
    let slot = Arc::clone(&lost);
    device.set_device_lost_callback(move |reason, message| {
        let why = match reason {
            wgpu::DeviceLostReason::Destroyed if message.is_empty() => {
                "the device was destroyed".to_owned()
            }
            wgpu::DeviceLostReason::Destroyed => format!("the device was destroyed ({message})"),
            wgpu::DeviceLostReason::Unknown if message.is_empty() => "no reason given".to_owned(),
            wgpu::DeviceLostReason::Unknown => message,
        };
        if let Ok(mut slot) = slot.lock() {
            slot.get_or_insert(why.clone());
        }
        tracing::error!("GPU device lost: {why}");
    });
    lost
}

fn instance(backend: Option<Backend>) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    if let Some(b) = backend {
        desc.backends = b.backends();
    }
    wgpu::Instance::new(desc)
}

fn backend_text(backend: Option<Backend>) -> String {
    backend.map_or(String::new(), |b| format!(" for backend {b:?}"))
}

/// One line describing an adapter: name, API and kind.
pub fn describe_adapter(info: &wgpu::AdapterInfo) -> String {
    let driver = if info.driver_info.is_empty() {
        String::new()
    } else {
        format!(", {}", info.driver_info)
    };
    format!(
        "{} ({:?}, {:?}{driver})",
        info.name, info.backend, info.device_type
    )
}

/// Every adapter wgpu can see for the backend filter.
pub fn list_adapters(backend: Option<Backend>) -> Vec<wgpu::AdapterInfo> {
    let instance = instance(backend);
    let backends = backend.map_or(wgpu::Backends::all(), Backend::backends);
    pollster::block_on(instance.enumerate_adapters(backends))
        .iter()
        .map(|a| a.get_info())
        .collect()
}

impl GpuContext {
    /// Opens the adapter wgpu prefers (high performance first), asking for the adapter's
    /// own limits: the WebGPU defaults are too small for large scenes, and on GL too small
    /// for compute at all.
    ///
    /// Without an explicit backend, the native APIs (Vulkan, Metal, DX12) are tried first
    /// and GL only when none of them has an adapter: initialising GL where Vulkan works
    /// costs time and fills the terminal with EGL warnings.
    pub fn new(backend: Option<Backend>) -> Result<Arc<Self>, GpuError> {
        let request = |backends: wgpu::Backends| {
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
            desc.backends = backends;
            let instance = wgpu::Instance::new(desc);
            pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            }))
        };
        let adapter = match backend {
            Some(b) => request(b.backends()),
            None => request(wgpu::Backends::PRIMARY).or_else(|_| request(wgpu::Backends::GL)),
        }
        .map_err(|e| GpuError::NoAdapter {
            backend: backend_text(backend),
            reason: e.to_string(),
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        if !adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
        {
            return Err(GpuError::NoAdapter {
                backend: backend_text(backend),
                reason: format!("{} cannot run compute shaders", describe_adapter(&info)),
            });
        }
        Self::open_device(adapter, limits)
    }

    /// A device of its own on `adapter`, asking for `limits`.
    fn open_device(adapter: wgpu::Adapter, limits: wgpu::Limits) -> Result<Arc<Self>, GpuError> {
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("kiln"),
            required_features: device_features(&adapter),
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: describe_adapter(&info),
            reason: e.to_string(),
        })?;
        // Errors are caught with error scopes where they can happen; anything that
        // escapes is logged instead of wgpu's default panic.
        device.on_uncaptured_error(Arc::new(|e: wgpu::Error| {
            tracing::error!("uncaptured wgpu error: {e}");
        }));
        let lost = watch_for_loss(&device);
        let (storage_texels, texel_reads) = texel_reads_for(&adapter, &device);
        Ok(Arc::new(Self {
            adapter,
            device,
            queue,
            pipelines: pipeline_cache_for(&info),
            info,
            pipelines_compiled: Default::default(),
            lost,
            rehearsal: Default::default(),
            storage_texels,
            texel_reads,
        }))
    }

    /// A second device on this context's adapter, with its own queue and pipeline cache:
    /// for work whose submissions must not hold up this device's. A software driver
    /// (lavapipe) compiles a kernel at its first dispatch, inside the submission, and every
    /// other submission to that device waits for it: the editor's window, whose frames
    /// are submissions, froze for a thumbnail's compile.
    pub fn sibling(&self) -> Result<Arc<Self>, GpuError> {
        Self::open_device(self.adapter.clone(), self.adapter.limits())
    }

    /// From now on a renderer whose kernel this context has not compiled first builds a
    /// small copy of itself on `other` (a [`sibling`](Self::sibling)), where the driver
    /// compiles it, and only then its own. On a software driver that compiles at the first
    /// dispatch (lavapipe) the compile then holds up `other`'s submissions, not this
    /// device's, and this device's compile finds the machine code in the driver's shader
    /// cache. Work of this context whose result comes back to the host, not to this
    /// device (a world graph's bake, `world_bake::bake_world`), runs on `other` whole.
    /// Does nothing on other adapters, whose drivers compile when the pipeline is
    /// created, outside any submission; set once.
    pub fn rehearse_compiles_on(&self, other: Arc<GpuContext>) {
        if self.info.device_type == wgpu::DeviceType::Cpu && other.device != self.device {
            let _ = self.rehearsal.set(other);
        }
    }

    /// The context [`rehearse_compiles_on`](Self::rehearse_compiles_on) named, if any.
    pub fn rehearsal(&self) -> Option<&Arc<GpuContext>> {
        self.rehearsal.get()
    }

    /// Wraps a device another part of the program opened (the editor's window, whose
    /// eframe renderer and Kiln's renderer share one device): the caller asked it for the
    /// adapter's own limits, as [`GpuContext::new`] does.
    pub fn from_device(
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Arc<Self>, GpuError> {
        let info = adapter.get_info();
        if !adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
        {
            return Err(GpuError::NoAdapter {
                backend: String::new(),
                reason: format!("{} cannot run compute shaders", describe_adapter(&info)),
            });
        }
        let lost = watch_for_loss(&device);
        let (storage_texels, texel_reads) = texel_reads_for(&adapter, &device);
        Ok(Arc::new(Self {
            adapter,
            device,
            queue,
            pipelines: pipeline_cache_for(&info),
            info,
            pipelines_compiled: Default::default(),
            lost,
            rehearsal: Default::default(),
            storage_texels,
            texel_reads,
        }))
    }

    pub fn describe(&self) -> String {
        describe_adapter(&self.info)
    }

    /// Why the device was lost, if it was.
    pub fn lost(&self) -> Option<String> {
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// An error naming `during` if the device has been lost.
    pub fn check_lost(&self, during: &str) -> Result<(), GpuError> {
        match self.lost() {
            Some(reason) => Err(GpuError::DeviceLost {
                adapter: self.describe(),
                during: during.into(),
                reason,
            }),
            None => Ok(()),
        }
    }

    /// How many compute pipelines this context has compiled; a kernel source served from
    /// the pipeline cache does not count.
    pub fn pipelines_compiled(&self) -> usize {
        self.pipelines_compiled
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// How many compiled pipelines the cache holds now (at most
    /// [`pipeline_cache_capacity`]).
    pub fn pipelines_cached(&self) -> usize {
        self.pipelines.lock().map_or(0, |p| p.len())
    }

    /// How many compiled pipelines the cache keeps at most.
    pub fn pipeline_capacity(&self) -> usize {
        self.pipelines.lock().map_or(0, |p| p.capacity)
    }

    /// Keeps at most `capacity` compiled pipelines from now on (at least one), dropping
    /// the least recently used beyond it. Renderers keep the pipelines they hold.
    pub fn set_pipeline_capacity(&self, capacity: usize) {
        if let Ok(mut cache) = self.pipelines.lock() {
            cache.set_capacity(capacity);
        }
    }

    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }
}

/// Pipelines a context keeps compiled. Each holds the driver's machine code for a whole
/// kernel (the editor soak measured about 300 MB of resident memory per compile on
/// lavapipe, docs/RELIABILITY.md), and an editor session compiles one for every change of
/// a graph's structure: the least recently used are dropped beyond this many. A scene
/// uses a few at a time (its kernel's entry points, the editor's previews).
pub const PIPELINE_CACHE_CAPACITY: usize = 32;

/// What one compiled pipeline holds of the host's memory on a CPU adapter, whose
/// pipelines are machine code in the process: measured by the editor soak on lavapipe
/// (docs/RELIABILITY.md).
pub const CPU_PIPELINE_BYTES: u64 = 300 << 20;

/// How many pipelines a context on an adapter of `device_type` keeps: at most
/// [`PIPELINE_CACHE_CAPACITY`], and on a CPU adapter no more than a quarter of the
/// `available` memory holds at [`CPU_PIPELINE_BYTES`] each, but at least 4 (a scene's
/// kernel entry points and the editor's previews).
pub fn pipeline_cache_capacity(device_type: wgpu::DeviceType, available: Option<u64>) -> usize {
    match (device_type, available) {
        (wgpu::DeviceType::Cpu, Some(bytes)) => usize::try_from(bytes / 4 / CPU_PIPELINE_BYTES)
            .unwrap_or(usize::MAX)
            .clamp(4, PIPELINE_CACHE_CAPACITY),
        _ => PIPELINE_CACHE_CAPACITY,
    }
}

/// A pipeline cache sized for `info`'s adapter and the memory free now.
fn pipeline_cache_for(
    info: &wgpu::AdapterInfo,
) -> std::sync::Mutex<PipelineCache<PipelineKey, wgpu::ComputePipeline>> {
    let capacity =
        pipeline_cache_capacity(info.device_type, super::film_pieces::available_memory());
    std::sync::Mutex::new(PipelineCache::with_capacity(capacity))
}

/// A compiled pipeline's key: the hash of its kernel's source and layouts, and of its entry
/// point (so that every pipeline of one kernel can be dropped at once).
pub(crate) type PipelineKey = (u64, u64);

/// A cache of at most `capacity` values by key that drops the least recently used first.
#[derive(Debug)]
pub(crate) struct PipelineCache<K, V> {
    entries: std::collections::HashMap<K, (V, u64)>,
    capacity: usize,
    /// Incremented on every use; an entry's stamp is its last use.
    clock: u64,
}

impl<K, V> Default for PipelineCache<K, V> {
    fn default() -> Self {
        Self::with_capacity(PIPELINE_CACHE_CAPACITY)
    }
}

impl<K, V> PipelineCache<K, V> {
    pub(crate) fn with_capacity(capacity: usize) -> Self {
        Self {
            entries: Default::default(),
            capacity: capacity.max(1),
            clock: 0,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.entries.len()
    }
}

impl<K: std::hash::Hash + Eq + Copy, V> PipelineCache<K, V> {
    pub(crate) fn contains(&self, key: K) -> bool {
        self.entries.contains_key(&key)
    }

    /// Drops the entries whose key `keep` refuses.
    pub(crate) fn retain(&mut self, keep: impl Fn(&K) -> bool) {
        self.entries.retain(|key, _| keep(key));
    }

    /// Adds `value` as the most recently used, dropping the least recently used when full.
    pub(crate) fn insert(&mut self, key: K, value: V) {
        self.clock += 1;
        if !self.entries.contains_key(&key) && self.entries.len() >= self.capacity {
            self.drop_oldest();
        }
        self.entries.insert(key, (value, self.clock));
    }

    /// Keeps at most `capacity` entries (at least one), the most recently used.
    pub(crate) fn set_capacity(&mut self, capacity: usize) {
        self.capacity = capacity.max(1);
        while self.entries.len() > self.capacity {
            self.drop_oldest();
        }
    }

    fn drop_oldest(&mut self) {
        let oldest = self
            .entries
            .iter()
            .min_by_key(|(_, (_, used))| *used)
            .map(|(&k, _)| k);
        if let Some(oldest) = oldest {
            self.entries.remove(&oldest);
        }
    }
}

impl<K: std::hash::Hash + Eq + Copy, V: Clone> PipelineCache<K, V> {
    /// The value of `key`, which becomes the most recently used.
    pub(crate) fn get(&mut self, key: K) -> Option<V> {
        self.clock += 1;
        let entry = self.entries.get_mut(&key)?;
        entry.1 = self.clock;
        Some(entry.0.clone())
    }
}

/// Gives the C heap's free pages back to the system (glibc's `malloc_trim`); elsewhere
/// does nothing. On a CPU adapter a device's buffers and its pipelines' compile are host
/// allocations made by many threads, and glibc keeps what they free in per-thread arenas:
/// an editor session on lavapipe held 1.5 GiB of freed heap beside 0.5 GiB in use. A
/// long-running caller (the editor) calls it now and then.
pub fn release_free_host_memory() {
    // SAFETY: malloc_trim only returns free pages of the allocator's own arenas.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::malloc_trim(0);
    }
}

#[cfg(test)]
mod tests {
    use super::{PIPELINE_CACHE_CAPACITY, PipelineCache, pipeline_cache_capacity};

    #[test]
    fn a_cpu_adapter_keeps_as_many_pipelines_as_a_quarter_of_free_memory_holds() {
        const GIB: u64 = 1 << 30;
        let gpu = wgpu::DeviceType::DiscreteGpu;
        let cpu = wgpu::DeviceType::Cpu;
        assert_eq!(
            pipeline_cache_capacity(gpu, Some(GIB)),
            PIPELINE_CACHE_CAPACITY
        );
        assert_eq!(pipeline_cache_capacity(cpu, None), PIPELINE_CACHE_CAPACITY);
        // 20 GiB free: 5 GiB for pipelines of 300 MiB.
        assert_eq!(pipeline_cache_capacity(cpu, Some(20 * GIB)), 17);
        assert_eq!(pipeline_cache_capacity(cpu, Some(2 * GIB)), 4);
        assert_eq!(
            pipeline_cache_capacity(cpu, Some(1024 * GIB)),
            PIPELINE_CACHE_CAPACITY
        );
    }

    #[test]
    fn the_pipeline_cache_drops_the_least_recently_used_beyond_its_capacity() {
        let mut cache = PipelineCache::with_capacity(3);
        for key in 0..3 {
            cache.insert(key, key * 10);
        }
        // 0 used again: 1 is now the least recently used.
        assert_eq!(cache.get(0), Some(0));
        cache.insert(3, 30);
        assert_eq!(cache.len(), 3);
        assert!(!cache.contains(1), "the least recently used is dropped");
        assert!(cache.contains(0) && cache.contains(2) && cache.contains(3));
        // Replacing a value that is there drops nothing.
        cache.insert(2, 21);
        assert_eq!((cache.len(), cache.get(2)), (3, Some(21)));
        // A thousand kernels later it still holds three.
        for key in 100..1100 {
            cache.insert(key, key);
        }
        assert_eq!(cache.len(), 3);
        assert!(cache.contains(1099) && cache.contains(1098) && cache.contains(1097));
        // A smaller capacity keeps the most recently used.
        assert_eq!(cache.get(1097), Some(1097));
        cache.set_capacity(1);
        assert_eq!(cache.len(), 1);
        assert!(cache.contains(1097));
        cache.set_capacity(0);
        assert_eq!(cache.len(), 1, "a cache keeps one at least");
    }
}
