//! Checkpoints of a long render (`kiln render --checkpoint-every`, `--resume`): the film's
//! state on the device between two passes ([`super::Renderer::film_state`]), the sample
//! index every pixel has reached, and a key of the scene and settings it belongs to.
//! Written atomically next to the output, so a crash or a full disk leaves the previous
//! checkpoint whole; resuming from one continues the render bit for bit.
//!
//! The file: `KILNCKPT`, a format version, the key, width, height and next sample
//! (little-endian), then each buffer as a length and its bytes.

use std::fmt::Write as _;
use std::hash::Hasher;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use super::RenderSettings;
use crate::scene::Scene;

const MAGIC: &[u8; 8] = b"KILNCKPT";
/// 2: the film's sums are fixed point (`crate::film::ExactFilm`), no longer Kahan sums.
const VERSION: u32 = 2;

/// What a checkpoint holds.
#[derive(Debug, PartialEq)]
pub struct Checkpoint {
    /// [`key`] of the scene and settings.
    pub key: u64,
    pub width: u32,
    pub height: u32,
    /// The first sample index not yet in every pixel.
    pub next_sample: u32,
    pub film: Vec<Vec<u8>>,
}

/// Where the checkpoint of a render writing `output` lives: beside it.
pub fn path_for(output: &Path) -> PathBuf {
    let mut name = output.file_name().unwrap_or_default().to_os_string();
    name.push(".kiln-checkpoint");
    output.with_file_name(name)
}

/// A stable 64-bit hash (FNV-1a) of a value's `Debug` text, which prints every field and
/// floats exactly, and of Kiln's version: the same on every machine running this version.
/// Streamed, never held as one string (a scene's meshes print long).
pub fn debug_hash(value: &dyn std::fmt::Debug) -> u64 {
    struct Hashing(fnv::FnvHasher);
    impl std::fmt::Write for Hashing {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            self.0.write(s.as_bytes());
            Ok(())
        }
    }
    let mut h = Hashing(fnv::FnvHasher::default());
    let _ = write!(h, "{value:?}{}", env!("CARGO_PKG_VERSION"));
    h.0.finish()
}

/// The hash of the settings that decide a sample's value: all of them but the samples per
/// pixel (a resumed render may go on to more; the parts of a split render differ in it).
pub fn settings_hash(settings: &RenderSettings) -> u64 {
    debug_hash(&RenderSettings {
        samples_per_pixel: 0,
        ..*settings
    })
}

/// A hash of everything that decides a render's samples: the scene, the settings
/// ([`settings_hash`]), and the first sample index (a part of a split render starts past
/// 0). Another build may refuse an older checkpoint, never take a wrong one.
pub fn key(scene: &Scene, settings: &RenderSettings, first_sample: u32) -> u64 {
    debug_hash(&(scene, settings_hash(settings), first_sample))
}

impl Checkpoint {
    /// Writes the checkpoint to `path` atomically: the previous one stays until this one
    /// is whole.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        kiln_plugin_api::atomic::write_atomically(path, |w| {
            let mut put = |bytes: &[u8]| w.write_all(bytes).map_err(|e| e.to_string());
            put(MAGIC)?;
            put(&VERSION.to_le_bytes())?;
            put(&self.key.to_le_bytes())?;
            for v in [self.width, self.height, self.next_sample] {
                put(&v.to_le_bytes())?;
            }
            put(&(self.film.len() as u32).to_le_bytes())?;
            for buffer in &self.film {
                put(&(buffer.len() as u64).to_le_bytes())?;
                put(buffer)?;
            }
            Ok(())
        })
    }

    /// Reads the checkpoint at `path`; errors name the file and what is wrong with it.
    pub fn read(path: &Path) -> Result<Self, String> {
        let fail = |why: &str| format!("cannot resume from {}: {why}", path.display());
        let (file, size) =
            kiln_plugin_api::read::open_regular(path).map_err(|e| fail(&e.to_string()))?;
        let mut r = std::io::BufReader::new(file);
        let mut take = |n: usize| -> Result<Vec<u8>, String> {
            let mut bytes = vec![0; n];
            r.read_exact(&mut bytes)
                .map_err(|_| fail("the file is cut short"))?;
            Ok(bytes)
        };
        if take(8)? != MAGIC {
            return Err(fail("not a Kiln checkpoint"));
        }
        let u32_at = |b: Vec<u8>| u32::from_le_bytes(b.try_into().expect("4 bytes"));
        let version = u32_at(take(4)?);
        if version != VERSION {
            return Err(fail(&format!(
                "a checkpoint of format {version}, this Kiln reads {VERSION}"
            )));
        }
        let key = u64::from_le_bytes(take(8)?.try_into().expect("8 bytes"));
        let (width, height, next_sample) = (u32_at(take(4)?), u32_at(take(4)?), u32_at(take(4)?));
        let count = u32_at(take(4)?);
        let mut film = Vec::new();
        for _ in 0..count.min(64) {
            let len = u64::from_le_bytes(take(8)?.try_into().expect("8 bytes"));
            if len > size {
                return Err(fail("the file is cut short"));
            }
            film.push(take(len as usize)?);
        }
        Ok(Self {
            key,
            width,
            height,
            next_sample,
            film,
        })
    }

    /// Refuses a checkpoint made for another scene, other settings or another size.
    pub fn check(&self, path: &Path, key: u64, width: u32, height: u32) -> Result<(), String> {
        if self.key != key || (self.width, self.height) != (width, height) {
            return Err(format!(
                "cannot resume from {}: it was made for another scene or other settings \
                 ({}x{} px); render without --resume to start over",
                path.display(),
                self.width,
                self.height
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checkpoint_reads_back_as_written_and_a_cut_one_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png.kiln-checkpoint");
        let c = Checkpoint {
            key: 0x0123_4567_89ab_cdef,
            width: 3,
            height: 2,
            next_sample: 17,
            film: vec![vec![1, 2, 3, 4], vec![], vec![9; 100]],
        };
        c.write(&path).unwrap();
        assert_eq!(Checkpoint::read(&path).unwrap(), c);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 1]).unwrap();
        let e = Checkpoint::read(&path).unwrap_err();
        assert!(
            e.contains("cut short") && e.contains("a.png.kiln-checkpoint"),
            "{e}"
        );
        std::fs::write(&path, b"PNG....").unwrap();
        assert!(Checkpoint::read(&path).unwrap_err().contains("cut short"));
        std::fs::write(&path, b"PNG.....and more").unwrap();
        assert!(Checkpoint::read(&path).unwrap_err().contains("not a Kiln"));
        let e = c.check(&path, 1, 3, 2).unwrap_err();
        assert!(e.contains("another scene"), "{e}");
        assert_eq!(
            path_for(Path::new("out/x.png")),
            Path::new("out/x.png.kiln-checkpoint")
        );
    }
}
