//! Writing a file so that it is either complete or untouched: the bytes go to a temporary
//! file in the target's folder, which is renamed over the target only once it is complete
//! and synced. A failed or interrupted export never leaves a truncated image behind nor
//! destroys the previous one. The same convention as the host's `src/film/output.rs`;
//! shared by the bundled exporters.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

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
        .prefix(".kiln-")
        .suffix(".part")
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
