//! Writing a file so that it is either complete or untouched: the bytes go to a temporary
//! file in the target's folder, which is renamed over the target only once it is complete
//! and synced. A failed or interrupted export never leaves a truncated image behind nor
//! destroys the previous one. Every file the host or a bundled plugin writes goes through
//! it (the image writers of `kiln-formats`, the scene saver).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// The suffix of the temporary files [`write_atomically`] writes.
pub const PARTIAL_FILE_SUFFIX: &str = ".part";

/// The prefix of the temporary files [`write_atomically`] writes in this process: it holds
/// the process id, so that a process ended in the middle of a write (a second Ctrl-C) can
/// remove its own temporary files, and only those, with [`remove_partial_files`]. Exporter
/// plugins link their own copy of this crate but run in the same process, so they share it.
pub fn partial_file_prefix() -> String {
    format!(".kiln-{}-", std::process::id())
}

/// Removes the temporary files this process has left in `dir` (see
/// [`partial_file_prefix`]); for a process about to exit in the middle of a write.
pub fn remove_partial_files(dir: &Path) {
    let prefix = partial_file_prefix();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with(&prefix) && name.ends_with(PARTIAL_FILE_SUFFIX) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Writes `path` through `write`, atomically. Errors name `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&mut File>) -> Result<(), String>,
) -> Result<(), String> {
    let fail = |message: String| format!("cannot write {}: {message}", path.display());
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut temp = tempfile::Builder::new()
        .prefix(&partial_file_prefix())
        .suffix(PARTIAL_FILE_SUFFIX)
        .tempfile_in(dir)
        .map_err(|e| {
            fail(format!(
                "cannot create a temporary file in {}: {e}",
                dir.display()
            ))
        })?;
    {
        let mut writer = BufWriter::new(temp.as_file_mut());
        write(&mut writer).map_err(fail)?;
        writer.flush().map_err(|e| fail(e.to_string()))?;
    }
    temp.as_file().sync_all().map_err(|e| fail(e.to_string()))?;
    // Temporary files are private (0600 on Unix); the image should be as readable as any
    // other file the user writes, or keep the permissions of the file it replaces.
    if let Some(permissions) = final_permissions(path) {
        std::fs::set_permissions(temp.path(), permissions).map_err(|e| fail(e.to_string()))?;
    }
    temp.persist(path).map_err(|e| fail(e.error.to_string()))?;
    Ok(())
}

fn final_permissions(path: &Path) -> Option<std::fs::Permissions> {
    if let Ok(existing) = std::fs::metadata(path) {
        return Some(existing.permissions());
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        Some(std::fs::Permissions::from_mode(0o644))
    }
    #[cfg(not(unix))]
    None
}
