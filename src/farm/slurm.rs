//! `kiln farm`: a render as a Slurm job array. `kiln farm slurm` writes a farm folder: the
//! job's description (`farm.ron`), an array script whose task `T` renders one part of one
//! frame (`render.sbatch`), and a merge script that joins each frame's parts
//! (`merge.sbatch`), submitted as a job that depends on the array. `kiln farm status`
//! compares the parts on disk and the tasks in Slurm's queue with what the job needs, and
//! `kiln farm resubmit` reruns only the tasks whose part is neither written nor queued.
//!
//! Task `T` of a job of `P` parts per frame renders frame `F₀ + T / P`, part `p = T mod P`:
//! samples `p·S/P .. (p+1)·S/P` of `S` per pixel. The array script computes the same in
//! shell arithmetic, so one script serves the whole array and any subset of it (Slurm's
//! `--array=2,5` reruns tasks 2 and 5), and a Kubernetes Indexed Job runs it with its
//! completion index (docs/SCALE_OUT.md). The farm folder must be on storage every node
//! sees, as the scene and the kiln executable must.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde::{Deserialize, Serialize};

use super::frame_path;
use super::part::read_part_header;

/// The job description's file in a farm folder.
pub const JOB_FILE: &str = "farm.ron";
pub const RENDER_SCRIPT: &str = "render.sbatch";
pub const MERGE_SCRIPT: &str = "merge.sbatch";

/// A render split into tasks, as `kiln farm slurm` wrote it into its folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FarmJob {
    /// The kiln executable the tasks run (absolute).
    pub kiln: PathBuf,
    /// The scene (absolute); none for the bundled Cornell box.
    pub scene: Option<PathBuf>,
    /// The merged image (absolute); with frames, numbered per frame ([`frame_path`]).
    pub output: PathBuf,
    /// Samples per pixel of each frame.
    pub spp: u32,
    /// Parts per frame.
    pub parts: u32,
    /// The frames of a turntable, if the job is an animation.
    pub frames: Option<Range<u32>>,
    /// The turntable's degrees over `frames`.
    pub turntable: Option<f32>,
    /// Further `kiln render` flags every task passes (`--size`, `--seed`, …).
    pub render_args: Vec<String>,
    /// Further `#SBATCH` options of both scripts (`--partition=…`, `--time=…`).
    pub sbatch_args: Vec<String>,
    /// The job arrays submitted so far, oldest first.
    pub submissions: Vec<Submission>,
}

/// One `sbatch` of the array (all tasks, or those resubmitted) and its merge job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    pub render_job: String,
    pub tasks: Vec<u32>,
    pub merge_job: String,
}

/// What one task renders.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub frame: Option<u32>,
    pub part: u32,
    pub samples: Range<u32>,
}

/// Where a task stands.
#[derive(Clone, Debug, PartialEq)]
pub enum TaskState {
    /// Its part is written and holds its samples.
    Done,
    /// In Slurm's queue, with the state squeue gives (`PENDING`, `RUNNING`, …).
    Queued(String),
    /// Never submitted.
    NotSubmitted,
    /// Submitted, no longer queued, and no part: it failed or was cancelled. The last
    /// line of its log, when there is one.
    Missing(Option<String>),
}

impl FarmJob {
    /// The number of frames (1 for a still).
    pub fn frame_count(&self) -> u32 {
        self.frames.as_ref().map_or(1, |f| f.len() as u32)
    }

    pub fn task_count(&self) -> u32 {
        self.frame_count() * self.parts
    }

    /// What task `t` renders.
    pub fn task(&self, t: u32) -> Task {
        let part = t % self.parts;
        let (spp, parts) = (self.spp as u64, self.parts as u64);
        let at = |p: u64| (p * spp / parts) as u32;
        Task {
            frame: self.frames.as_ref().map(|f| f.start + t / self.parts),
            part,
            samples: at(part as u64)..at(part as u64 + 1),
        }
    }

    /// The part file task `t` writes.
    pub fn part_path(&self, dir: &Path, t: u32) -> PathBuf {
        let task = self.task(t);
        let path = dir.join("parts").join(format!("part{}.exr", task.part));
        match task.frame {
            // What `kiln render --frame` makes of the script's `part$PART_####.exr`.
            Some(frame) => frame_path(
                &path.with_file_name(format!("part{}_####.exr", task.part)),
                frame,
            ),
            None => path,
        }
    }

    /// The merged image of `frame` (None for a still).
    pub fn output_of(&self, frame: Option<u32>) -> PathBuf {
        match frame {
            Some(f) => frame_path(&self.output, f),
            None => self.output.clone(),
        }
    }

    fn sbatch_header(&self, name: &str, log: &str) -> String {
        let mut s = format!("#!/bin/bash\n#SBATCH --job-name={name}\n#SBATCH --output={log}\n");
        for arg in &self.sbatch_args {
            let _ = writeln!(s, "#SBATCH {arg}");
        }
        s
    }

    /// The job-array script: task `$SLURM_ARRAY_TASK_ID` renders its part.
    pub fn render_script(&self, dir: &Path) -> String {
        let logs = dir.join("logs").join("render_%A_%a.log");
        let mut s = self.sbatch_header("kiln-render", &logs.to_string_lossy());
        let _ = writeln!(s, "#SBATCH --array=0-{}", self.task_count() - 1);
        s.push_str(
            "# Written by `kiln farm slurm`; `kiln farm resubmit` reruns some tasks with --array.\n\
             set -euo pipefail\n\
             T=${SLURM_ARRAY_TASK_ID:?run as a job array task}\n",
        );
        let _ = writeln!(s, "PARTS={} SPP={}", self.parts, self.spp);
        s.push_str(
            "PART=$(( T % PARTS ))\n\
             A=$(( PART * SPP / PARTS )) B=$(( (PART + 1) * SPP / PARTS ))\n",
        );
        let parts = quote(&dir.join("parts").to_string_lossy());
        let mut command = vec![quote(&self.kiln.to_string_lossy()), "render".into()];
        if let Some(scene) = &self.scene {
            command.push(quote(&scene.to_string_lossy()));
        }
        command.extend(["--spp".into(), "\"$SPP\"".into()]);
        command.extend(["--samples".into(), "\"$A..$B\"".into()]);
        match &self.frames {
            Some(frames) => {
                let _ = writeln!(s, "FRAME=$(( {} + T / PARTS ))", frames.start);
                let _ = writeln!(s, "OUT={parts}/part${{PART}}_####.exr");
                command.extend([
                    "--frames".into(),
                    format!("{}..{}", frames.start, frames.end),
                    "--frame".into(),
                    "\"$FRAME\"".into(),
                ]);
                if let Some(degrees) = self.turntable {
                    command.extend(["--turntable".into(), degrees.to_string()]);
                }
            }
            None => {
                let _ = writeln!(s, "OUT={parts}/part$PART.exr");
            }
        }
        command.extend(["-o".into(), "\"$OUT\"".into(), "--quiet".into()]);
        command.extend(self.render_args.iter().map(|a| quote(a)));
        let _ = writeln!(s, "exec {}", command.join(" "));
        s
    }

    /// The merge script: each frame's parts into its image.
    pub fn merge_script(&self, dir: &Path) -> String {
        let logs = dir.join("logs").join("merge_%j.log");
        let mut s = self.sbatch_header("kiln-merge", &logs.to_string_lossy());
        s.push_str("# Written by `kiln farm slurm`: runs once every part is rendered.\nset -euo pipefail\n");
        let kiln = quote(&self.kiln.to_string_lossy());
        let parts = quote(&dir.join("parts").to_string_lossy());
        let frames: Vec<Option<u32>> = match &self.frames {
            Some(f) => f.clone().map(Some).collect(),
            None => vec![None],
        };
        for frame in frames {
            let pattern = match frame {
                Some(f) => frame_path(Path::new("part*_####.exr"), f)
                    .to_string_lossy()
                    .into_owned(),
                None => "part*.exr".into(),
            };
            let output = quote(&self.output_of(frame).to_string_lossy());
            let _ = writeln!(s, "{kiln} merge {parts}/{pattern} -o {output}");
        }
        s
    }

    /// Tasks whose part is missing or does not hold its samples.
    fn done(&self, dir: &Path, t: u32) -> bool {
        let task = self.task(t);
        read_part_header(&self.part_path(dir, t))
            .is_ok_and(|h| h.samples == task.samples && h.frame == task.frame)
    }
}

/// Quotes `s` for bash: as it is when it is plainly safe, else in single quotes.
fn quote(s: &str) -> String {
    let safe = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
    if safe {
        s.to_owned()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// The farm folder of `output` when none is given: beside it, named after it without the
/// frame number's `#`s (`shot_####.png` → `shot.farm`).
pub fn default_dir(output: &Path) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().replace('#', ""))
        .unwrap_or_default();
    let stem = stem.trim_end_matches(['_', '-', '.', ' ']);
    output.with_file_name(format!(
        "{}.farm",
        if stem.is_empty() { "render" } else { stem }
    ))
}

/// Writes the farm folder: `farm.ron`, the two scripts, and `parts/` and `logs/`.
pub fn write_farm(dir: &Path, job: &FarmJob) -> Result<(), String> {
    // An #SBATCH line ends at a space and at a `#`: the logs' path cannot hold either.
    let text = dir.to_string_lossy();
    if text.contains(|c: char| c.is_whitespace() || c == '#' || c == '%') {
        return Err(format!(
            "the farm folder {text} has a space, # or % in its path, which #SBATCH --output cannot hold: choose another with --dir"
        ));
    }
    let fail = |e: std::io::Error| format!("cannot write the farm folder {}: {e}", dir.display());
    for sub in ["parts", "logs"] {
        std::fs::create_dir_all(dir.join(sub)).map_err(fail)?;
    }
    save_job(dir, job)?;
    for (name, text) in [
        (RENDER_SCRIPT, job.render_script(dir)),
        (MERGE_SCRIPT, job.merge_script(dir)),
    ] {
        kiln_plugin_api::atomic::write_atomically(&dir.join(name), |w| {
            w.write_all(text.as_bytes()).map_err(|e| e.to_string())
        })
        .map_err(|e| format!("cannot write {}: {e}", dir.join(name).display()))?;
    }
    Ok(())
}

fn save_job(dir: &Path, job: &FarmJob) -> Result<(), String> {
    let path = dir.join(JOB_FILE);
    let text = ron::ser::to_string_pretty(job, ron::ser::PrettyConfig::default())
        .map_err(|e| e.to_string())?;
    kiln_plugin_api::atomic::write_atomically(&path, |w| {
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Reads the job of the farm folder `dir`.
pub fn read_farm(dir: &Path) -> Result<FarmJob, String> {
    let path = dir.join(JOB_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!(
            "{} is not a farm folder (kiln farm slurm writes one): cannot read {}: {e}",
            dir.display(),
            path.display()
        )
    })?;
    ron::from_str(&text).map_err(|e| format!("{} is damaged: {e}", path.display()))
}

/// Runs a Slurm command, its output as text; errors say what failed.
fn slurm(program: &str, args: &[&str]) -> Result<String, String> {
    let output = Command::new(program).args(args).output().map_err(|e| {
        format!("cannot run {program}: {e} (is Slurm's client, slurm-client, installed?)")
    })?;
    if !output.status.success() {
        return Err(format!(
            "{program} {} failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&output.stderr).trim()
        ));
    }
    Ok(String::from_utf8_lossy(&output.stdout).into_owned())
}

/// Submits the array's `tasks` (all when None) and a merge job that runs once they all
/// succeed; records both in the farm's job file.
pub fn submit(dir: &Path, job: &mut FarmJob, tasks: Option<&[u32]>) -> Result<Submission, String> {
    let render = dir.join(RENDER_SCRIPT);
    let merge = dir.join(MERGE_SCRIPT);
    let tasks: Vec<u32> = match tasks {
        Some(t) => t.to_vec(),
        None => (0..job.task_count()).collect(),
    };
    let list = tasks
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(",");
    let array = format!("--array={list}");
    let job_id = |out: String| out.trim().split(';').next().unwrap_or_default().to_owned();
    let render_job = job_id(slurm(
        "sbatch",
        &["--parsable", &array, &render.to_string_lossy()],
    )?);
    let dependency = format!("--dependency=afterok:{render_job}");
    let merge_job = job_id(slurm(
        "sbatch",
        &["--parsable", &dependency, &merge.to_string_lossy()],
    )?);
    let submission = Submission {
        render_job,
        tasks,
        merge_job,
    };
    job.submissions.push(submission.clone());
    save_job(dir, job)?;
    Ok(submission)
}

/// The queued jobs and array tasks, by job id and array index (None for a job that is no
/// array), with their states.
fn queue() -> Result<BTreeMap<(String, Option<u32>), String>, String> {
    let text = slurm("squeue", &["-h", "-r", "-o", "%i %T"])?;
    let mut queued = BTreeMap::new();
    for line in text.lines() {
        let Some((id, state)) = line.trim().split_once(' ') else {
            continue;
        };
        let key = match id.split_once('_') {
            Some((job, index)) => (job.to_owned(), index.parse().ok()),
            None => (id.to_owned(), None),
        };
        queued.insert(key, state.trim().to_owned());
    }
    Ok(queued)
}

/// The last line of a task's log, where its error is.
fn last_log_line(dir: &Path, job: &str, task: u32) -> Option<String> {
    let log = dir.join("logs").join(format!("render_{job}_{task}.log"));
    let text = std::fs::read_to_string(log).ok()?;
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map(|l| l.trim().to_owned())
}

/// The farm's state: each task's, and the merge job's.
pub struct FarmStatus {
    pub tasks: Vec<TaskState>,
    /// The latest merge job's state in the queue, if it is queued.
    pub merge_queued: Option<String>,
    /// Frames whose merged image exists.
    pub merged: Vec<Option<u32>>,
}

/// Reads the parts on disk and Slurm's queue.
pub fn status(dir: &Path, job: &FarmJob) -> Result<FarmStatus, String> {
    let queued = if job.submissions.is_empty() {
        BTreeMap::new()
    } else {
        queue()?
    };
    let tasks = (0..job.task_count())
        .map(|t| {
            if job.done(dir, t) {
                return TaskState::Done;
            }
            // The latest submission of the task decides.
            let Some(s) = job.submissions.iter().rev().find(|s| s.tasks.contains(&t)) else {
                return TaskState::NotSubmitted;
            };
            match queued.get(&(s.render_job.clone(), Some(t))) {
                Some(state) => TaskState::Queued(state.clone()),
                None => TaskState::Missing(last_log_line(dir, &s.render_job, t)),
            }
        })
        .collect();
    let merge_queued = job
        .submissions
        .last()
        .and_then(|s| queued.get(&(s.merge_job.clone(), None)).cloned());
    let frames: Vec<Option<u32>> = match &job.frames {
        Some(f) => f.clone().map(Some).collect(),
        None => vec![None],
    };
    let merged = frames
        .into_iter()
        .filter(|&f| job.output_of(f).exists())
        .collect();
    Ok(FarmStatus {
        tasks,
        merge_queued,
        merged,
    })
}

/// Submits again the tasks whose part is neither written nor queued (cancelling a merge job
/// still waiting on a failed array), with a new merge job. None when nothing is missing.
pub fn resubmit(dir: &Path, job: &mut FarmJob) -> Result<Option<Submission>, String> {
    let state = status(dir, job)?;
    let missing: Vec<u32> = state
        .tasks
        .iter()
        .enumerate()
        .filter(|(_, s)| matches!(s, TaskState::Missing(_)))
        .map(|(t, _)| t as u32)
        .collect();
    if missing.is_empty() {
        return Ok(None);
    }
    if state.merge_queued.is_some()
        && let Some(s) = job.submissions.last()
    {
        slurm("scancel", &[&s.merge_job])?;
    }
    submit(dir, job, Some(&missing)).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(frames: Option<Range<u32>>) -> FarmJob {
        FarmJob {
            kiln: "/opt/kiln bin/kiln".into(),
            scene: Some("/scenes/a.kiln".into()),
            output: "/out/shot_####.png".into(),
            spp: 100,
            parts: 3,
            frames,
            turntable: Some(360.0),
            render_args: vec!["--size".into(), "64x48".into()],
            sbatch_args: vec!["--partition=render".into()],
            submissions: Vec::new(),
        }
    }

    #[test]
    fn tasks_cover_every_frame_and_sample_once() {
        let j = job(Some(10..14));
        assert_eq!(j.task_count(), 12);
        let mut seen = Vec::new();
        for t in 0..j.task_count() {
            let task = j.task(t);
            seen.push((task.frame.unwrap(), task.samples));
        }
        for frame in 10..14 {
            let ranges: Vec<Range<u32>> = seen
                .iter()
                .filter(|(f, _)| *f == frame)
                .map(|(_, r)| r.clone())
                .collect();
            assert_eq!(ranges, vec![0..33, 33..66, 66..100]);
        }
        assert_eq!(
            j.part_path(Path::new("/farm"), 5),
            Path::new("/farm/parts/part2_0011.exr")
        );
        assert_eq!(j.output_of(Some(12)), Path::new("/out/shot_0012.png"));
    }

    #[test]
    fn the_scripts_run_the_task_arithmetic_and_quote_paths() {
        let j = job(Some(10..14));
        let script = j.render_script(Path::new("/farm"));
        assert!(script.contains("#SBATCH --array=0-11\n"), "{script}");
        assert!(script.contains("#SBATCH --partition=render\n"));
        assert!(script.contains("FRAME=$(( 10 + T / PARTS ))"));
        assert!(
            script.contains(
                "exec '/opt/kiln bin/kiln' render /scenes/a.kiln --spp \"$SPP\" --samples \"$A..$B\" --frames 10..14 --frame \"$FRAME\" --turntable 360 -o \"$OUT\" --quiet --size 64x48"
            ),
            "{script}"
        );
        let merge = j.merge_script(Path::new("/farm"));
        assert!(merge.contains(
            "'/opt/kiln bin/kiln' merge /farm/parts/part*_0013.exr -o /out/shot_0013.png"
        ));
        assert_eq!(quote("it's"), "'it'\\''s'");
    }

    #[test]
    fn the_array_script_computes_what_the_job_says() {
        // Runs the script's arithmetic in bash for every task, the render replaced by echo.
        let j = job(Some(10..14));
        let script = j
            .render_script(Path::new("/farm"))
            .replace("exec '/opt/kiln bin/kiln' render", "echo");
        for t in 0..j.task_count() {
            let out = Command::new("bash")
                .arg("-c")
                .arg(&script)
                .env("SLURM_ARRAY_TASK_ID", t.to_string())
                .output()
                .expect("bash runs");
            let text = String::from_utf8_lossy(&out.stdout);
            let task = j.task(t);
            let expected = format!(
                "--samples {}..{} --frames 10..14 --frame {} --turntable 360 -o /farm/parts/part{}_####.exr --quiet",
                task.samples.start,
                task.samples.end,
                task.frame.unwrap(),
                task.part
            );
            assert!(
                text.contains(&expected),
                "task {t}: {text} lacks {expected}"
            );
        }
    }

    #[test]
    fn the_default_farm_folder_has_no_frame_marks() {
        assert_eq!(
            default_dir(Path::new("/o/shot_####.png")),
            Path::new("/o/shot.farm")
        );
        assert_eq!(
            default_dir(Path::new("/o/final.exr")),
            Path::new("/o/final.farm")
        );
        let e = write_farm(Path::new("/tmp/a b"), &job(None)).unwrap_err();
        assert!(e.contains("choose another with --dir"), "{e}");
    }

    #[test]
    fn a_farm_folder_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let j = job(None);
        write_farm(dir.path(), &j).unwrap();
        assert_eq!(read_farm(dir.path()).unwrap(), j);
        let e = read_farm(&dir.path().join("parts")).unwrap_err();
        assert!(e.contains("is not a farm folder"), "{e}");
        let state = status(dir.path(), &j).unwrap();
        assert!(state.tasks.iter().all(|t| *t == TaskState::NotSubmitted));
    }
}
