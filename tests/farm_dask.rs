//! The render farm on a real engine (run by `scripts/test`, about a minute): a Dask
//! scheduler and two workers on 127.0.0.1, `scripts/farm` submits 8 shards, one
//! worker's process group is killed while it renders a shard, the shard is rerun on
//! the other worker, and the merged image is bit-identical to a single-machine render.
//! The render names an environment map relative to the farm's directory, so the
//! workers (started elsewhere) read it only if the farm ships it.
//!
//! Needs the farm's virtual environment (`scripts/farm --setup`, or
//! `EMBER_FARM_PYTHON`), so it is ignored by a plain `cargo test`; scripts/test runs it
//! with `--ignored`. Every wait has a time limit; every process started here is
//! stopped by its process group id, whatever happens.

use crate::common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SCENE: &str = "scenes/cs184/sky/CBspheres_lambertian.dae";
/// One shard takes ~0.5-2 s at -t 1 on a shared machine: long enough to be caught
/// rendering, short enough for a test of about a minute.
const RENDER: [&str; 10] = ["-t", "1", "-s", "2048", "-m", "3", "-r", "64", "64", "-q"];

fn python() -> PathBuf {
    std::env::var_os("EMBER_FARM_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(ROOT).join(".cache/farm/bin/python"))
}

/// Processes started by this test, each in its own process group; all are killed on drop.
struct Group(Vec<(String, Child)>);

impl Group {
    fn spawn(&mut self, name: &str, cmd: &mut Command, log: &Path) -> u32 {
        use std::os::unix::process::CommandExt;
        let log = fs::File::create(log).unwrap();
        let child = cmd
            .process_group(0)
            .stdin(Stdio::null())
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let pid = child.id();
        self.0.push((name.into(), child));
        pid
    }

    fn kill(&mut self, name: &str) {
        if let Some((_, c)) = self.0.iter_mut().find(|(n, _)| n == name) {
            kill_group(c.id());
            let _ = c.wait();
        }
    }

    /// Waits at most `limit` for `name` to exit; its success.
    fn wait(&mut self, name: &str, limit: Duration) -> bool {
        let (_, c) = self.0.iter_mut().find(|(n, _)| n == name).unwrap();
        let t0 = Instant::now();
        while t0.elapsed() < limit {
            if let Some(st) = c.try_wait().unwrap() {
                return st.success();
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        panic!("{name} did not finish within {limit:?}");
    }
}

impl Drop for Group {
    fn drop(&mut self) {
        for (_, c) in &mut self.0 {
            if c.try_wait().ok().flatten().is_none() {
                kill_group(c.id());
                let _ = c.wait();
            }
        }
    }
}

fn kill_group(pgid: u32) {
    let _ = Command::new("kill")
        .args(["-KILL", "--", &format!("-{pgid}")])
        .status();
}

/// Polls `f` every 20 ms for at most `limit`.
fn wait_for<T>(what: &str, limit: Duration, mut f: impl FnMut() -> Option<T>) -> T {
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        if let Some(v) = f() {
            return v;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    panic!("timed out after {limit:?} waiting for {what}");
}

/// The `--shard` argument of an ember process whose parent is `parent`, if one runs.
fn ember_child_shard(parent: u32) -> Option<String> {
    for entry in fs::read_dir("/proc").ok()?.flatten() {
        let Ok(stat) = fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // pid (comm) state ppid ...: comm may contain spaces, so split after ')'.
        let ppid = stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().nth(1))
            .and_then(|p| p.parse::<u32>().ok());
        if ppid != Some(parent) {
            continue;
        }
        let cmdline = fs::read(entry.path().join("cmdline")).unwrap_or_default();
        let args: Vec<String> = cmdline
            .split(|&b| b == 0)
            .map(|a| String::from_utf8_lossy(a).into_owned())
            .collect();
        if let Some(i) = args.iter().position(|a| a == "--shard") {
            return args.get(i + 1).cloned();
        }
    }
    None
}

fn pixel_bits(path: &Path) -> Vec<[u32; 3]> {
    let img = ember::image_io::read_image(path).unwrap_or_else(|e| panic!("{e}"));
    img.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

#[test]
#[ignore = "needs Dask (scripts/farm --setup); scripts/test runs it"]
fn dask_farm_survives_a_killed_worker_and_merges_bit_identically() {
    let py = python();
    assert!(
        py.exists(),
        "{}: no farm environment (run scripts/farm --setup)",
        py.display()
    );
    let dask = py.with_file_name("dask");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ember = env!("CARGO_BIN_EXE_ember");
    let scene = Path::new(ROOT).join(SCENE);
    let sched_file = d.join("scheduler.json");
    let mut procs = Group(Vec::new());

    procs.spawn(
        "scheduler",
        Command::new(&dask)
            .args([
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
            ])
            .arg(&sched_file),
        &d.join("scheduler.log"),
    );
    let address = wait_for("the scheduler file", Duration::from_secs(60), || {
        let text = fs::read_to_string(&sched_file).ok()?;
        let v: serde_json::Value = serde_json::from_str(&text).ok()?;
        v["address"].as_str().map(String::from)
    });
    let mut worker_pid = Vec::new();
    for name in ["w1", "w2"] {
        let pid = procs.spawn(
            name,
            Command::new(&dask)
                .args([
                    "worker",
                    &address,
                    "--name",
                    name,
                    "--nthreads",
                    "1",
                    "--no-nanny",
                ])
                .args([
                    "--host",
                    "127.0.0.1",
                    "--no-dashboard",
                    "--death-timeout",
                    "60",
                ]),
            &d.join(format!("{name}.log")),
        );
        worker_pid.push(pid);
    }

    // An environment map named relative to the farm's directory, which the workers
    // (started elsewhere) can only read if the farm ships it with the tasks.
    fs::copy(
        Path::new(ROOT).join("scenes/env_sun.exr"),
        d.join("sun.exr"),
    )
    .unwrap();
    let env = ["-e", "sun.exr"];

    // The single-machine render.
    let single = d.join("single.exr");
    common::run(
        common::command()
            .current_dir(d)
            .args(RENDER)
            .args(env)
            .arg("-f")
            .arg(&single)
            .arg(&scene),
    )
    .success();

    let merged = d.join("merged.exr");
    let farm_log = d.join("farm.log");
    procs.spawn(
        "farm",
        Command::new(&py)
            .current_dir(d)
            .arg(Path::new(ROOT).join("scripts/farm"))
            .args([
                "--scheduler",
                &address,
                "--shards",
                "8",
                "--wait-workers",
                "2",
            ])
            .args(["--timeout", "60", "--ember", ember, "--"])
            .args(RENDER)
            .args(env)
            .arg("-f")
            .arg(&merged)
            .arg(&scene),
        &farm_log,
    );
    // Kill w1's whole process group as soon as it renders a shard.
    let killed = wait_for("w1 to render a shard", Duration::from_secs(90), || {
        ember_child_shard(worker_pid[0])
    });
    procs.kill("w1");
    let ok = procs.wait("farm", Duration::from_secs(180));
    let log = fs::read_to_string(&farm_log).unwrap();
    assert!(ok, "scripts/farm failed:\n{log}");

    // Every shard finished once in the log; the killed one on w2.
    for k in 0..8 {
        let line = format!("shard {k}/8 done on ");
        assert_eq!(log.matches(&line).count(), 1, "shard {k}/8:\n{log}");
    }
    assert!(
        log.contains(&format!("shard {killed} done on w2")),
        "shard {killed} (killed on w1) was not rerun on w2:\n{log}"
    );
    assert!(
        pixel_bits(&merged) == pixel_bits(&single),
        "the merged image differs from the single-machine render"
    );
    eprintln!("killed w1 while it rendered shard {killed}; rerun on w2; merged image bit-identical\n{log}");
}
