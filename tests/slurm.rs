//! `kiln farm` on a real Slurm: a single-node cluster started for the test
//! (`tests/slurm/cluster.sh`, which needs root and Debian's slurmctld, slurmd,
//! slurm-client and munge; `.ci/run` installs them). A render split into a 4-task job array
//! merges to the bits of a single-process render; a cancelled task is named by
//! `kiln farm status` and `kiln farm resubmit` completes the render, again bit for bit.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use common::exr::read_exr;

const CLUSTER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/slurm/cluster.sh");

/// A running single-node cluster, stopped when dropped.
struct Cluster {
    dir: tempfile::TempDir,
    conf: PathBuf,
}

impl Cluster {
    fn start() -> Self {
        let missing: Vec<&str> = ["slurmctld", "slurmd", "sbatch", "munged"]
            .into_iter()
            .filter(|p| {
                !Command::new("sh")
                    .args(["-c", &format!("command -v {p} || test -x /usr/sbin/{p}")])
                    .output()
                    .is_ok_and(|o| o.status.success())
            })
            .collect();
        assert!(
            missing.is_empty(),
            "Slurm is not installed ({missing:?} missing): apt-get install -y --no-install-recommends slurmctld slurmd slurm-client munge (.ci/run does)"
        );
        let dir = tempfile::tempdir().expect("a temporary folder");
        let out = Command::new("bash")
            .args([CLUSTER, "start"])
            .arg(dir.path())
            .output()
            .expect("cluster.sh runs");
        assert!(
            out.status.success(),
            "the test cluster did not start (it needs root): {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let conf = dir.path().join("slurm.conf");
        Self { dir, conf }
    }

    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    fn kiln(&self, work: &Path, args: &[&str]) -> Output {
        self.command(env!("CARGO_BIN_EXE_kiln"))
            .args(args)
            .current_dir(work)
            .output()
            .expect("kiln runs")
    }

    /// Waits until Slurm's queue is empty.
    fn wait_idle(&self) {
        let start = Instant::now();
        loop {
            let out = self
                .command("squeue")
                .args(["-h", "-o", "%i %T"])
                .output()
                .expect("squeue runs");
            if out.status.success() && out.stdout.iter().all(u8::is_ascii_whitespace) {
                return;
            }
            assert!(
                start.elapsed() < Duration::from_secs(300),
                "jobs still queued after 300 s: {}",
                String::from_utf8_lossy(&out.stdout)
            );
            std::thread::sleep(Duration::from_millis(250));
        }
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .args([CLUSTER, "stop"])
            .arg(self.dir.path())
            .output();
    }
}

fn ok(out: Output) -> String {
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "kiln failed: {text}");
    text
}

fn assert_same_image(a: &Path, b: &Path) {
    let (a_image, b_image) = (read_exr(a), read_exr(b));
    for c in ["R", "G", "B"] {
        let same = a_image
            .channel(c)
            .iter()
            .zip(b_image.channel(c))
            .all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(
            same,
            "channel {c} of {} differs from {}",
            a.display(),
            b.display()
        );
    }
}

#[test]
fn a_job_array_renders_the_bits_of_one_process_and_a_cancelled_task_is_resubmitted() {
    let cluster = Cluster::start();
    let work = tempfile::tempdir().unwrap();
    let w = work.path();
    let size = ["--", "--size", "32x24"];
    ok(cluster.kiln(
        w,
        &[
            "render",
            "--spp",
            "16",
            "--size",
            "32x24",
            "-q",
            "-o",
            "whole.exr",
        ],
    ));

    // Four parts of 16 spp through Slurm, merged by the dependent job.
    let submit = |output: &str| {
        let args = [
            "farm", "slurm", "--parts", "4", "--spp", "16", "-o", output, "--submit",
        ];
        ok(cluster.kiln(w, &[&args[..], &size].concat()))
    };
    let said = submit("farmed.exr");
    assert!(said.contains("submitted job array"), "{said}");
    cluster.wait_idle();
    let farm = w.join("farmed.farm");
    let status = ok(cluster.kiln(w, &["farm", "status", farm.to_str().unwrap()]));
    assert!(status.contains("4 of 4 parts rendered"), "{status}");
    assert_same_image(&w.join("farmed.exr"), &w.join("whole.exr"));

    // One task cancelled before it runs: its merge job is cancelled with it (Slurm's
    // kill_invalid_depend), status names the missing range, and resubmit completes it.
    submit("again.exr");
    let farm = w.join("again.farm");
    let job = kiln::farm::slurm::read_farm(&farm).unwrap();
    let array = &job.submissions[0].render_job;
    let cancel = cluster
        .command("scancel")
        .arg(format!("{array}_3"))
        .output()
        .unwrap();
    assert!(
        cancel.status.success(),
        "{}",
        String::from_utf8_lossy(&cancel.stderr)
    );
    cluster.wait_idle();
    assert!(
        !w.join("again.exr").exists(),
        "the merge ran without a part"
    );
    let out = cluster.kiln(w, &["farm", "status", farm.to_str().unwrap()]);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        !out.status.success(),
        "status says nothing is missing: {text}"
    );
    assert!(text.contains("3 of 4 parts rendered"), "{text}");
    assert!(
        text.contains("task 3 (samples 12..16): missing, failed or cancelled"),
        "{text}"
    );
    assert!(text.contains("kiln farm resubmit"), "{text}");
    let said = ok(cluster.kiln(w, &["farm", "resubmit", farm.to_str().unwrap()]));
    assert!(said.contains("resubmitted task(s) [3]"), "{said}");
    cluster.wait_idle();
    let status = ok(cluster.kiln(w, &["farm", "status", farm.to_str().unwrap()]));
    assert!(status.contains("4 of 4 parts rendered"), "{status}");
    assert_same_image(&w.join("again.exr"), &w.join("whole.exr"));
    let said = ok(cluster.kiln(w, &["farm", "resubmit", farm.to_str().unwrap()]));
    assert!(said.contains("nothing to resubmit"), "{said}");
}
