//! Reading a whole file whose size is bounded: only regular files (a FIFO would block, a
//! device such as `/dev/zero` never ends), and no more than a limit, checked while reading
//! rather than from the size the file system reports (which is 0 for such files). Every
//! file the host or a bundled plugin reads whole goes through it.

use std::io::Read;
use std::path::Path;

/// The most bytes a scene, material or mesh file is read up to: a file larger than this is
/// refused rather than read into memory.
pub const MAX_FILE_BYTES: u64 = 1 << 31;

/// Opens `path` for reading if it is a regular file (asked before opening: opening a
/// FIFO blocks until something writes to it), with its size. For files read in part
/// (a header, a bounded prefix); [`read_bounded`] reads a whole one.
pub fn open_regular(path: &Path) -> std::io::Result<(std::fs::File, u64)> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        ));
    }
    Ok((std::fs::File::open(path)?, metadata.len()))
}

/// The bytes of the regular file at `path`, refused if it holds more than `limit`.
pub fn read_bounded(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let (file, size) = open_regular(path)?;
    let mut bytes = Vec::with_capacity(size.min(limit) as usize);
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("larger than the {limit} bytes Kiln reads"),
        ));
    }
    Ok(bytes)
}

/// [`read_bounded`] for text: the file must also be UTF-8.
pub fn read_text_bounded(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_bounded(path, limit)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_files_over_the_limit_are_refused_and_others_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.txt");
        std::fs::write(&path, "12345").unwrap();
        assert_eq!(read_bounded(&path, 5).unwrap(), b"12345");
        assert_eq!(read_text_bounded(&path, 5).unwrap(), "12345");
        let over = read_bounded(&path, 4).unwrap_err();
        assert!(
            over.to_string().contains("larger than the 4 bytes"),
            "{over}"
        );
        // A device reports size 0 and never ends; a folder is not a file either.
        for not_a_file in [Path::new("/dev/zero"), dir.path()] {
            let e = read_bounded(not_a_file, 1 << 20).unwrap_err();
            assert!(
                e.to_string().contains("not a regular file"),
                "{}: {e}",
                not_a_file.display()
            );
            let e = open_regular(not_a_file).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let (_, size) = open_regular(&path).unwrap();
        assert_eq!(size, 5);
        std::fs::write(&path, b"\xff").unwrap();
        assert!(read_text_bounded(&path, 5).is_err());
    }
}
