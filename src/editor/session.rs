//! What the editor keeps between runs in its state folder (`$XDG_STATE_HOME/kiln`): the
//! recent files, the viewport's preferences, and the autosave that brings work back after
//! a crash.
//!
//! Each running editor autosaves into a folder of its own, `recovery/<pid>/`, and removes
//! it when it closes normally; a folder left by a process that is no longer running is
//! what a crash leaves, and the next start offers it. Writes are atomic (the scene writer
//! and a renamed temporary file), so a crash during an autosave leaves the previous one.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::SystemTime;

use crate::scene::{self, Scene};

/// How many recent files File ▸ Open Recent lists.
pub const RECENT_FILES: usize = 10;

/// The editor's state folder.
#[derive(Clone, Debug)]
pub struct SessionStore {
    dir: PathBuf,
}

/// An autosave a previous editor left behind.
#[derive(Clone, Debug, PartialEq)]
pub struct Recovery {
    /// The autosaved scene.
    pub scene: PathBuf,
    /// The file the work came from, if it had one.
    pub source: Option<PathBuf>,
    pub saved_at: SystemTime,
}

/// The viewport's settings that are the user's rather than a document's (Blender keeps
/// them in its preferences): kept in `viewport.txt` as `key=value` lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewportPreferences {
    /// Screen pixels per viewport pixel along each axis.
    pub pixel_size: u32,
    /// Samples per pixel after which the viewport rests.
    pub max_samples: u32,
}

impl Default for ViewportPreferences {
    /// A pixel per pixel, and [`DEFAULT_SAMPLE_LIMIT`](super::DEFAULT_SAMPLE_LIMIT).
    fn default() -> Self {
        Self {
            pixel_size: 1,
            max_samples: super::DEFAULT_SAMPLE_LIMIT,
        }
    }
}

impl ViewportPreferences {
    fn to_text(self) -> String {
        format!(
            "pixel_size={}\nmax_samples={}\n",
            self.pixel_size, self.max_samples
        )
    }

    /// Reads what `to_text` wrote: a line that is not a known key with a valid value keeps
    /// the default (a file from another version still opens).
    fn from_text(text: &str) -> Self {
        let mut p = Self::default();
        for (key, value) in text.lines().filter_map(|l| l.split_once('=')) {
            let Ok(value) = value.trim().parse::<u32>() else {
                continue;
            };
            match key.trim() {
                "pixel_size" if super::app::PIXEL_SIZES.contains(&value) => p.pixel_size = value,
                "max_samples" if value >= 1 => p.max_samples = value,
                _ => {}
            }
        }
        p
    }
}

const AUTOSAVE_NAME: &str = "autosave.kiln";
const SOURCE_NAME: &str = "source.txt";

impl SessionStore {
    pub fn new(dir: PathBuf) -> Self {
        Self { dir }
    }

    /// The platform's state folder for Kiln: `$XDG_STATE_HOME/kiln`, else
    /// `~/.local/state/kiln`; None without a home folder.
    pub fn default_dir() -> Option<PathBuf> {
        std::env::var_os("XDG_STATE_HOME")
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
            .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".local/state")))
            .map(|d| d.join("kiln"))
    }

    fn recent_file(&self) -> PathBuf {
        self.dir.join("recent.txt")
    }

    /// The recent files, most recent first, those that no longer exist left out.
    pub fn recent(&self) -> Vec<PathBuf> {
        let Ok(text) = std::fs::read_to_string(self.recent_file()) else {
            return Vec::new();
        };
        text.lines()
            .filter(|l| !l.is_empty())
            .map(PathBuf::from)
            .filter(|p| p.exists())
            .take(RECENT_FILES)
            .collect()
    }

    /// Puts `path` first in the recent files.
    pub fn add_recent(&self, path: &Path) -> Result<(), String> {
        let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned());
        let mut recent = self.recent();
        recent.retain(|p| *p != path);
        recent.insert(0, path);
        recent.truncate(RECENT_FILES);
        let text: String = recent
            .iter()
            .map(|p| format!("{}\n", p.display()))
            .collect();
        write_atomically(&self.recent_file(), text.as_bytes())
    }

    fn preferences_file(&self) -> PathBuf {
        self.dir.join("viewport.txt")
    }

    /// The viewport's preferences as last saved, the defaults where none were.
    pub fn viewport_preferences(&self) -> ViewportPreferences {
        std::fs::read_to_string(self.preferences_file()).map_or_else(
            |_| ViewportPreferences::default(),
            |text| ViewportPreferences::from_text(&text),
        )
    }

    pub fn save_viewport_preferences(&self, p: ViewportPreferences) -> Result<(), String> {
        write_atomically(&self.preferences_file(), p.to_text().as_bytes())
    }

    fn recovery_dir(&self, pid: u32) -> PathBuf {
        self.dir.join("recovery").join(pid.to_string())
    }

    /// Autosaves `scene` (with the images it embeds) for this process, noting the file
    /// it came from.
    pub fn autosave(
        &self,
        scene: &Scene,
        images: &[(String, Arc<Vec<u8>>)],
        source: Option<&Path>,
    ) -> Result<(), String> {
        let dir = self.recovery_dir(std::process::id());
        std::fs::create_dir_all(&dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        scene::save_scene(scene, &dir.join(AUTOSAVE_NAME), images).map_err(|e| e.to_string())?;
        let source = source.map_or(String::new(), |p| p.display().to_string());
        write_atomically(&dir.join(SOURCE_NAME), source.as_bytes())
    }

    /// Removes this process's autosave (a normal close).
    pub fn clear_autosave(&self) {
        let _ = std::fs::remove_dir_all(self.recovery_dir(std::process::id()));
    }

    /// The newest autosave left by an editor that is no longer running.
    pub fn recovery(&self) -> Option<Recovery> {
        let entries = std::fs::read_dir(self.dir.join("recovery")).ok()?;
        entries
            .filter_map(Result::ok)
            .filter(|e| {
                e.file_name()
                    .to_str()
                    .and_then(|n| n.parse::<u32>().ok())
                    .is_some_and(|pid| pid != std::process::id() && !process_is_running(pid))
            })
            .filter_map(|e| {
                let scene = e.path().join(AUTOSAVE_NAME);
                let saved_at = std::fs::metadata(&scene).ok()?.modified().ok()?;
                let source = std::fs::read_to_string(e.path().join(SOURCE_NAME))
                    .ok()
                    .filter(|s| !s.is_empty())
                    .map(PathBuf::from);
                Some(Recovery {
                    scene,
                    source,
                    saved_at,
                })
            })
            .max_by_key(|r| r.saved_at)
    }

    /// Removes the autosave of `recovery` (recovered or declined).
    pub fn discard(&self, recovery: &Recovery) {
        if let Some(dir) = recovery.scene.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// Whether a process with this id is running (on Linux, by `/proc`; elsewhere assumed
/// not, so an autosave is always offered).
pub fn process_is_running(pid: u32) -> bool {
    Path::new("/proc").join(pid.to_string()).exists()
}

fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let fail = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    std::fs::create_dir_all(dir).map_err(fail)?;
    let mut file = tempfile::NamedTempFile::new_in(dir).map_err(fail)?;
    file.write_all(bytes).map_err(fail)?;
    file.persist(path).map_err(|e| fail(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewport_preferences_round_trip_and_bad_lines_keep_the_defaults() {
        let dir = tempfile::tempdir().unwrap();
        let store = SessionStore::new(dir.path().join("state"));
        let defaults = ViewportPreferences::default();
        assert_eq!(store.viewport_preferences(), defaults);
        let chosen = ViewportPreferences {
            pixel_size: 4,
            max_samples: 64,
        };
        store.save_viewport_preferences(chosen).unwrap();
        assert_eq!(store.viewport_preferences(), chosen);
        std::fs::write(
            store.preferences_file(),
            "pixel_size=3\nmax_samples=0\nwhat=1\nno equals sign\n",
        )
        .unwrap();
        assert_eq!(store.viewport_preferences(), defaults);
    }

    #[test]
    fn recent_files_are_most_recent_first_without_repeats() {
        let dir = tempfile::tempdir().unwrap();
        let store = SessionStore::new(dir.path().join("state"));
        let files: Vec<PathBuf> = (0..12)
            .map(|i| {
                let p = dir.path().join(format!("s{i}.kiln"));
                std::fs::write(&p, "").unwrap();
                std::fs::canonicalize(&p).unwrap()
            })
            .collect();
        for f in &files {
            store.add_recent(f).unwrap();
        }
        store.add_recent(&files[5]).unwrap();
        let recent = store.recent();
        assert_eq!(recent.len(), RECENT_FILES);
        assert_eq!(recent[0], files[5]);
        assert_eq!(recent[1], files[11]);
        std::fs::remove_file(&files[11]).unwrap();
        assert!(
            !store.recent().contains(&files[11]),
            "missing files drop out"
        );
    }

    #[test]
    fn an_autosave_of_a_dead_process_is_offered_and_ours_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let store = SessionStore::new(dir.path().to_owned());
        let scene = crate::scene::default_scene().unwrap();
        store
            .autosave(&scene, &[], Some(Path::new("/work/box.kiln")))
            .unwrap();
        assert_eq!(store.recovery(), None, "this process is still running");
        // What a crashed editor leaves: its folder under a pid no process has.
        let dead = dir.path().join("recovery").join(u32::MAX.to_string());
        std::fs::rename(store.recovery_dir(std::process::id()), &dead).unwrap();
        let recovery = store.recovery().expect("offered");
        assert_eq!(
            recovery.source.as_deref(),
            Some(Path::new("/work/box.kiln"))
        );
        let back = crate::scene::load_scene(&recovery.scene).unwrap();
        assert_eq!(back.instances.len(), scene.instances.len());
        store.discard(&recovery);
        assert_eq!(store.recovery(), None);
    }
}
