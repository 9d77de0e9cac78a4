//! `ember report --quick`: the page has all six sections and every image it links;
//! the command printed under a figure renders the same pixels; and the page loads in
//! a real browser (headless Chromium) with every image, no console error, and
//! something on screen.
//!
//! The report is made once per test run and shared by the tests.

use crate::common;

use common::cli::ember_in;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The repository: the report runs here, so its commands name scenes as `scenes/...`.
fn repo() -> PathBuf {
    common::repo("")
}

/// The folder of the quick report, made on first use (kept under the target folder
/// for a look after the tests).
fn report() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-quick");
        let _ = std::fs::remove_dir_all(&out);
        let out_arg = out.to_string_lossy().into_owned();
        let run = ember_in(&repo(), ["report", "--quick", "--out", &out_arg]).success();
        assert!(
            run.stdout().contains("index.html"),
            "ember report: {}",
            run.stdout()
        );
        out
    })
}

fn read(file: &str) -> String {
    let p = report().join(file);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Every `](target)` of a Markdown text.
fn markdown_links(md: &str) -> Vec<String> {
    md.match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &md[i + 2..];
            rest.find(')').map(|end| rest[..end].to_string())
        })
        .collect()
}

/// Every `src="..."` of an HTML text.
fn html_sources(html: &str) -> Vec<String> {
    html.match_indices("src=\"")
        .filter_map(|(i, _)| {
            let rest = &html[i + 5..];
            rest.find('"').map(|end| rest[..end].to_string())
        })
        .collect()
}

#[test]
fn the_page_has_every_part_and_every_image_it_links() {
    let md = read("README.md");
    let html = read("index.html");
    for (id, title) in [
        ("part1", "Ray generation"),
        ("part2", "Bounding volume hierarchy"),
        ("part3", "Direct illumination"),
        ("part4", "Global illumination"),
        ("part5", "Adaptive sampling"),
        ("part6", "Speed against accuracy"),
    ] {
        assert!(md.contains(&format!("<a id=\"{id}\">")), "README.md: {id}");
        assert!(md.contains(title), "README.md: {title}");
        assert!(
            html.contains(&format!("<section id=\"{id}\">")),
            "index.html: {id}"
        );
    }
    assert!(!html.contains("<script"), "the page needs no script");
    let images: Vec<String> = markdown_links(&md)
        .into_iter()
        .filter(|l| l.ends_with(".png"))
        .collect();
    assert_eq!(
        images,
        html_sources(&html),
        "the two files show the same images"
    );
    // Parts 1-5's figures (at least 40) and the convergence charts.
    assert!(images.len() >= 42, "{} images", images.len());
    assert!(
        images.iter().any(|i| i.starts_with("converge/")),
        "{images:?}"
    );
    for image in &images {
        assert!(!image.starts_with('/'), "{image}: not a relative link");
        let p = report().join(image);
        let (w, h) = image::image_dimensions(&p).unwrap_or_else(|e| panic!("{image}: {e}"));
        assert!(w > 0 && h > 0, "{image}");
    }
    // The timing table names the CPU and the backends.
    assert!(md.contains("no acceleration") && md.contains(&ember::image_metadata::cpu_model()));
}

/// Every command of the README (the text in backquotes) whose `-f` names a file `name`.
fn commands_writing(md: &str, name: &str) -> Vec<String> {
    let writes = |c: &str| {
        let words: Vec<&str> = c.split(' ').collect();
        let f = words.iter().position(|w| *w == "-f");
        f.and_then(|i| words.get(i + 1))
            .is_some_and(|out| Path::new(out).file_name() == Some(name.as_ref()))
    };
    md.split('`')
        .filter(|c| c.starts_with("ember ") && writes(c))
        .map(str::to_string)
        .collect()
}

/// The 8-bit pixels of a PNG.
fn pixels(path: &Path) -> Vec<u8> {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
        .into_raw()
}

/// Runs a printed `ember ...` command in the repository with its `-f` replaced by `out`.
fn run_printed(command: &str, out: &Path) {
    assert!(!command.contains('\''), "{command}: a quoted word");
    let mut words: Vec<String> = command.split(' ').skip(1).map(str::to_string).collect();
    let f = words.iter().position(|w| w == "-f").expect("-f") + 1;
    words[f] = out.to_string_lossy().into_owned();
    ember_in(&repo(), &words).success();
}

#[test]
fn printed_commands_render_their_figures_bit_for_bit() {
    let md = read("README.md");
    let tmp = tempfile::tempdir().unwrap();
    let figures = [
        "part1_CBspheres_lambertian.png",
        "part2_maxplanck.png",
        "part3_CBbunny_hemisphere_l4.png",
        "part3_CBspheres_lambertian_light_l16.png",
        "part4_CBbunny_m3_o0.png",
        "part4_CBspheres_lambertian_s16.png",
        "part5_CBbunny.png",
    ];
    for name in figures {
        let figure = report().join("figures").join(name);
        let printed = commands_writing(&md, name);
        assert!(!printed.is_empty(), "no command writes {name}");
        let out = tmp.path().join(name);
        run_printed(&printed[0], &out);
        assert!(
            pixels(&out) == pixels(&figure),
            "{name}: {} gives other pixels",
            printed[0]
        );
        let rate = figure.with_file_name(name.replace(".png", "_rate.png"));
        if rate.exists() {
            let ours = out.with_file_name(name.replace(".png", "_rate.png"));
            assert!(
                pixels(&ours) == pixels(&rate),
                "{name}: the sample-rate map differs"
            );
        }
    }
}

#[test]
fn the_indirect_figure_is_the_difference_of_its_two_commands() {
    let md = read("README.md");
    let tmp = tempfile::tempdir().unwrap();
    let full = commands_writing(&md, "full.exr");
    let minus = commands_writing(&md, "minus.exr");
    assert_eq!((full.len(), minus.len()), (1, 1), "{full:?} {minus:?}");
    let (a, b) = (tmp.path().join("full.exr"), tmp.path().join("minus.exr"));
    run_printed(&full[0], &a);
    run_printed(&minus[0], &b);
    let (a, b) = (
        ember::image_io::read_image(&a).unwrap(),
        ember::image_io::read_image(&b).unwrap(),
    );
    // The two renders share their paths up to the first bounce, so nothing is
    // subtracted that the longer paths did not add (but float rounding).
    let below = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x - *y).min_element());
    let lowest = below.fold(0f32, f32::min);
    assert!(
        lowest > -1e-4,
        "full − minus reaches {lowest}: the paths differ"
    );
    let diff: Vec<u8> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(x, y)| {
            let d = *x - *y;
            [d.x, d.y, d.z].map(ember::image_io::srgb8)
        })
        .collect();
    let figure = report().join("figures/part4_CBspheres_lambertian_indirect.png");
    assert!(
        diff == pixels(&figure),
        "the indirect figure is not full − minus"
    );
}

/// Headless Chromium driven over the DevTools protocol on a pipe (`--remote-debugging-pipe`:
/// requests on the child's fd 3, answers and events on its fd 4).
mod chromium {
    use serde_json::{json, Value};
    use std::io::{Read, Write};
    use std::os::fd::{FromRawFd, IntoRawFd, OwnedFd};
    use std::os::unix::process::CommandExt;
    use std::path::Path;
    use std::process::{Child, Command, Stdio};
    use std::sync::mpsc::{Receiver, RecvTimeoutError};
    use std::time::{Duration, Instant};

    /// The browser, if this machine has one.
    pub fn find() -> Option<&'static str> {
        ["chromium", "chromium-browser", "google-chrome"]
            .into_iter()
            .find(|b| {
                Command::new(b)
                    .arg("--version")
                    .output()
                    .is_ok_and(|o| o.status.success())
            })
    }

    pub struct Browser {
        child: Child,
        to: std::fs::File,
        from: Receiver<Value>,
        next_id: u64,
        /// Every event seen so far.
        pub events: Vec<Value>,
    }

    fn pipe() -> (OwnedFd, OwnedFd) {
        let mut fds = [0; 2];
        // SAFETY: `fds` has room for the two descriptors pipe(2) writes.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0, "pipe");
        // SAFETY: both descriptors were just opened and are owned by nothing else.
        unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) }
    }

    impl Browser {
        /// Starts `binary` headless with a fresh profile in `profile`, offline and quiet.
        pub fn start(binary: &str, profile: &Path) -> Browser {
            let (child_reads, we_write) = pipe();
            let (we_read, child_writes) = pipe();
            let (r, w) = (child_reads.into_raw_fd(), child_writes.into_raw_fd());
            let mut cmd = Command::new(binary);
            cmd.args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--remote-debugging-pipe",
                "--window-size=1280,1600",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
            // SAFETY: only dup2 and close, which are async-signal-safe, run in the child.
            unsafe {
                cmd.pre_exec(move || {
                    if libc::dup2(r, 3) < 0 || libc::dup2(w, 4) < 0 {
                        return Err(std::io::Error::last_os_error());
                    }
                    Ok(())
                });
            }
            let child = cmd.spawn().expect("start chromium");
            // SAFETY: the child has its copies; these ends are ours to close.
            unsafe {
                libc::close(r);
                libc::close(w);
            }
            let (tx, from) = std::sync::mpsc::channel();
            let mut reader = std::fs::File::from(we_read);
            std::thread::spawn(move || {
                let mut buf = Vec::new();
                let mut chunk = [0u8; 65536];
                while let Ok(n) = reader.read(&mut chunk) {
                    if n == 0 {
                        break;
                    }
                    buf.extend_from_slice(&chunk[..n]);
                    while let Some(end) = buf.iter().position(|&b| b == 0) {
                        let msg: Vec<u8> = buf.drain(..=end).collect();
                        if let Ok(v) = serde_json::from_slice(&msg[..msg.len() - 1]) {
                            if tx.send(v).is_err() {
                                return;
                            }
                        }
                    }
                }
            });
            Browser {
                child,
                to: std::fs::File::from(we_write),
                from,
                next_id: 1,
                events: Vec::new(),
            }
        }

        /// Sends `method` (to the page `session`, if given) and waits for its result.
        pub fn call(&mut self, session: Option<&str>, method: &str, params: Value) -> Value {
            let id = self.next_id;
            self.next_id += 1;
            let mut msg = json!({ "id": id, "method": method, "params": params });
            if let Some(s) = session {
                msg["sessionId"] = json!(s);
            }
            let mut bytes = serde_json::to_vec(&msg).unwrap();
            bytes.push(0);
            self.to.write_all(&bytes).expect("write to chromium");
            let reply = self.wait(|v| v["id"] == json!(id), method);
            if let Some(e) = reply.get("error") {
                panic!("chromium: {method}: {e}");
            }
            reply["result"].clone()
        }

        /// Waits (at most a minute) for the message `want` picks, keeping events.
        pub fn wait(&mut self, want: impl Fn(&Value) -> bool, what: &str) -> Value {
            let deadline = Instant::now() + Duration::from_secs(60);
            loop {
                let left = deadline.saturating_duration_since(Instant::now());
                match self.from.recv_timeout(left) {
                    Ok(v) if want(&v) => return v,
                    Ok(v) => {
                        if v.get("method").is_some() {
                            self.events.push(v);
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => panic!("chromium: no answer to {what}"),
                    Err(RecvTimeoutError::Disconnected) => panic!("chromium exited during {what}"),
                }
            }
        }
    }

    impl Drop for Browser {
        fn drop(&mut self) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

#[test]
#[ignore = "needs headless Chromium (Debian's chromium package, which scripts/install-deps installs); scripts/test runs it with --ignored"]
fn the_page_loads_in_headless_chromium() {
    use base64::Engine as _;
    use serde_json::{json, Value};
    let binary = chromium::find().expect(
        "no Chromium on this machine: scripts/install-deps installs Debian's chromium package",
    );
    let profile = tempfile::tempdir().unwrap();
    let mut b = chromium::Browser::start(binary, profile.path());
    let target = b.call(None, "Target.createTarget", json!({ "url": "about:blank" }));
    let attached = b.call(
        None,
        "Target.attachToTarget",
        json!({ "targetId": target["targetId"], "flatten": true }),
    );
    let session = attached["sessionId"].as_str().expect("session").to_string();
    let s = Some(session.as_str());
    for domain in ["Runtime.enable", "Log.enable", "Page.enable"] {
        b.call(s, domain, json!({}));
    }
    let url = format!("file://{}", report().join("index.html").display());
    b.call(s, "Page.navigate", json!({ "url": url }));
    b.wait(
        |v| v["method"] == "Page.loadEventFired",
        "the page's load event",
    );
    let state = b.call(
        s,
        "Runtime.evaluate",
        json!({
            "expression": "JSON.stringify({images: Array.from(document.images).map(i => [i.getAttribute('src'), i.complete && i.naturalWidth > 0]), text: document.body.innerText.length, height: document.documentElement.scrollHeight})",
            "returnByValue": true,
        }),
    );
    let state: Value =
        serde_json::from_str(state["result"]["value"].as_str().expect("value")).unwrap();
    let images = state["images"].as_array().expect("images");
    assert!(images.len() >= 42, "{} images", images.len());
    let broken: Vec<&Value> = images.iter().filter(|i| i[1] != json!(true)).collect();
    assert!(broken.is_empty(), "images that did not load: {broken:?}");
    assert!(state["text"].as_u64().unwrap() > 2000, "{state}");
    assert!(state["height"].as_u64().unwrap() > 3000, "{state}");
    let shot = b.call(s, "Page.captureScreenshot", json!({ "format": "png" }));
    let png = base64::engine::general_purpose::STANDARD
        .decode(shot["data"].as_str().expect("data"))
        .unwrap();
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-screenshot.png");
    std::fs::write(&path, &png).unwrap();
    eprintln!("screenshot: {}", path.display());
    let errors: Vec<&Value> = b
        .events
        .iter()
        .filter(|e| match e["method"].as_str() {
            Some("Runtime.exceptionThrown") => true,
            Some("Runtime.consoleAPICalled") => {
                matches!(e["params"]["type"].as_str(), Some("error" | "assert"))
            }
            Some("Log.entryAdded") => e["params"]["entry"]["level"] == "error",
            _ => false,
        })
        .collect();
    assert!(errors.is_empty(), "console errors: {errors:?}");
    // Not blank: a good part of the screen is neither white nor one flat colour.
    let img = image::load_from_memory(&png).unwrap().to_rgb8();
    let (w, h) = img.dimensions();
    assert!(w >= 800 && h >= 600, "{w}x{h}");
    let inked = img
        .pixels()
        .filter(|p| p.0.iter().any(|&c| c < 200))
        .count();
    let share = inked as f64 / (w * h) as f64;
    assert!(
        share > 0.05,
        "only {:.1} % of the screenshot is drawn",
        share * 100.0
    );
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort();
    colours.dedup();
    assert!(colours.len() > 100, "{} colours", colours.len());
}

#[test]
fn bad_report_input_is_a_one_line_error() {
    use common::cli::ember;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    let out = dir.path().join("out");
    let (out, file) = (out.to_str().unwrap(), file.to_str().unwrap());
    ember(["report", "--quick", "--out", file]).fails_with("is a file, not a folder");
    ember(["report", "--quick", "--out", out, "model.obj"]).fails_with("not .obj files");
    let (a, b) = (
        repo().join("scenes/cs184/sky/CBbunny.dae"),
        repo().join("scenes/cmu462/sky/CBbunny.dae"),
    );
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    ember(["report", "--quick", "--out", out, a, b]).fails_with("two scenes of the same name");
    ember([
        "report",
        "--quick",
        "--out",
        out,
        "--mitsuba",
        "/nonexistent/python",
    ])
    .fails_with("--mitsuba /nonexistent/python: no such file");
}
