//! `finestep view` and `finestep run --view` in a real browser: Debian's Chromium,
//! headless (`make setup` installs it), loads the page from the CLI's server; the page
//! writes into `#figures` what it drew (segments, bounding box, where the path lands on
//! the screen) and the live state it last saw, and the test holds those against the
//! figures the CLI printed. A screenshot (kept in `target/view/`) must show path-coloured
//! pixels where the page says the path projects. Chromium runs with `--no-sandbox` here
//! only: its sandbox needs user namespaces, which a root session in a container lacks.
//! `FINESTEP_CHROMIUM` names another browser binary.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

const WINDOW: (u32, u32) = (1200, 800);
/// The canvas's size on the page (`?size=`): the same in a DOM dump and a screenshot.
const CANVAS: &str = "?size=860x640";
/// The page's background (web/view.js BACKGROUND).
const BACKGROUND: [u8; 3] = [0x12, 0x16, 0x1b];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn out_dir() -> PathBuf {
    let dir = root().join("target/view");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A `finestep` process serving the view; killed when dropped.
struct Served {
    child: Child,
    lines: Receiver<String>,
    url: String,
    figures: serde_json::Value,
    output: Vec<String>,
}

impl Served {
    fn start(args: &[&str]) -> Served {
        let mut child = Command::new(env!("CARGO_BIN_EXE_finestep"))
            .args(args)
            .current_dir(root())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("run finestep");
        let stdout = child.stdout.take().unwrap();
        let (send, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if send.send(line).is_err() {
                    break;
                }
            }
        });
        let mut served = Served { child, lines, url: String::new(), figures: serde_json::Value::Null, output: vec![] };
        let figures = served.wait_for("view-figures ");
        served.figures = serde_json::from_str(&figures).unwrap();
        let url = served.wait_for("view: ");
        served.url = url.split_whitespace().next().unwrap().to_string();
        served
    }

    /// The rest of the first line of output starting with `prefix` (within 60 s).
    fn wait_for(&mut self, prefix: &str) -> String {
        let until = Instant::now() + Duration::from_secs(60);
        loop {
            let left = until.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.output.push(line.clone());
                    if let Some(rest) = line.trim_start().strip_prefix(prefix) {
                        return rest.to_string();
                    }
                }
                Err(_) => panic!("no `{prefix}` line from finestep; its output:\n{}", self.output.join("\n")),
            }
        }
    }

    fn addr(&self) -> String {
        self.url.trim_start_matches("http://").trim_end_matches('/').to_string()
    }
}

/// GET `path` from the server at `addr`: the body.
fn get(addr: &str, path: &str) -> String {
    let mut stream = std::net::TcpStream::connect(addr).unwrap();
    write!(stream, "GET {path} HTTP/1.0\r\nHost: test\r\n\r\n").unwrap();
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    text.split_once("\r\n\r\n").map(|(_, body)| body.to_string()).unwrap_or_default()
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs headless Chromium on `url` with `extra` arguments (up to 90 s): its stdout.
fn chromium(url: &str, extra: &[&str]) -> String {
    let binary = std::env::var("FINESTEP_CHROMIUM").unwrap_or_else(|_| "chromium".into());
    // A profile of its own for each browser (the two tests run side by side).
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let profile = std::env::temp_dir().join(format!("finestep-view-chromium-{}-{run}", std::process::id()));
    let window = format!("--window-size={},{}", WINDOW.0, WINDOW.1);
    let user_dir = format!("--user-data-dir={}", profile.display());
    let mut child = Command::new(&binary)
        .args(["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
        .args(["--force-device-scale-factor=1", "--hide-scrollbars", "--no-first-run", "--disable-extensions"])
        .args([window.as_str(), user_dir.as_str(), "--virtual-time-budget=10000"])
        .args(extra)
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("{binary}: {e} (Debian's chromium: `make setup` installs it)"));
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stdout.read_to_string(&mut text);
        text
    });
    let until = Instant::now() + Duration::from_secs(90);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > until {
            let _ = child.kill();
            panic!("{binary} did not finish within 90 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = std::fs::remove_dir_all(&profile);
    reader.join().unwrap()
}

/// The `data-*` attributes of the page's `#figures`, unescaped, by their DOM names
/// (`data-live-period` -> `live-period`).
fn dom_figures(html: &str) -> BTreeMap<String, String> {
    let start = html.find("<div id=\"figures\"").unwrap_or_else(|| panic!("no #figures in the page:\n{html}"));
    let tag = &html[start..start + html[start..].find('>').unwrap()];
    let mut out = BTreeMap::new();
    let mut rest = tag;
    while let Some(at) = rest.find(" data-") {
        rest = &rest[at + 6..];
        let (name, after) = rest.split_once("=\"").unwrap();
        let (value, after) = after.split_once('"').unwrap();
        out.insert(name.to_string(), value.replace("&quot;", "\"").replace("&amp;", "&"));
        rest = after;
    }
    out
}

fn number(figures: &BTreeMap<String, String>, name: &str) -> f64 {
    figures.get(name).unwrap_or_else(|| panic!("no data-{name} in {figures:?}")).parse().unwrap()
}

fn json(figures: &BTreeMap<String, String>, name: &str) -> serde_json::Value {
    serde_json::from_str(figures.get(name).unwrap_or_else(|| panic!("no data-{name} in {figures:?}"))).unwrap()
}

/// The page drew what the CLI computed, without errors.
fn check_drawn(figures: &BTreeMap<String, String>, cli: &serde_json::Value) {
    assert_eq!(figures.get("ready").map(String::as_str), Some("1"), "{figures:?}");
    assert!(!figures.contains_key("errors"), "the page reported errors: {figures:?}");
    for name in ["programmed-segments", "executed-segments"] {
        let key = name.replace('-', "_");
        assert_eq!(number(figures, name), cli[&key].as_f64().unwrap(), "{name}: {figures:?}");
    }
    assert_eq!(number(figures, "periods"), cli["periods"].as_f64().unwrap());
    let drawn = json(figures, "bbox");
    for corner in 0..2 {
        for axis in 0..3 {
            let (page, ours) = (drawn[corner][axis].as_f64().unwrap(), cli["bbox"][corner][axis].as_f64().unwrap());
            assert!((page - ours).abs() < 1e-4, "bbox[{corner}][{axis}]: page {page}, CLI {ours}");
        }
    }
}

/// A pixel of the path's colours: saturated (the feed scale's colours), or with `white`
/// near white (the positions read back during a run, drawn over the executed path),
/// where the background and the grid are dark grey.
fn path_coloured(p: &image::Rgb<u8>, white: bool) -> bool {
    let (max, min) = (p.0.iter().max().unwrap(), p.0.iter().min().unwrap());
    max - min > 60 || (white && *min > 200)
}

/// The screenshot shows the path: path-coloured pixels within 2 px of every probe the page
/// projected, none in the canvas's empty corner, and some thousand in all.
fn check_screenshot(path: &Path, figures: &BTreeMap<String, String>, white: bool) {
    let image = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    assert_eq!(image.dimensions(), WINDOW);
    let canvas = json(figures, "canvas");
    let (w, h) = (canvas[0].as_u64().unwrap() as u32, canvas[1].as_u64().unwrap() as u32);
    assert_eq!(image.get_pixel(2, h - 3).0, BACKGROUND, "the canvas's corner is not the background");
    let coloured =
        (0..w).flat_map(|x| (0..h).map(move |y| (x, y))).filter(|&(x, y)| path_coloured(image.get_pixel(x, y), white));
    let count = coloured.count();
    assert!(count > 1000, "{count} path-coloured pixels in {}", path.display());
    for probe in json(figures, "probes").as_array().unwrap() {
        let (x, y) = (probe[0].as_i64().unwrap(), probe[1].as_i64().unwrap());
        assert!(x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h, "probe {probe} outside the canvas");
        let hit = (-2..=2).flat_map(|dx| (-2..=2).map(move |dy| (x + dx, y + dy))).any(|(px, py)| {
            px >= 0
                && py >= 0
                && (px as u32) < w
                && (py as u32) < h
                && path_coloured(image.get_pixel(px as u32, py as u32), white)
        });
        assert!(hit, "no path pixel near {probe} in {}", path.display());
    }
    println!("  {}: {count} path-coloured pixels, every probe on the path", path.display());
}

fn program() -> String {
    "tests/view/pocket.ngc".to_string()
}

/// `finestep view`: the page draws both paths as the CLI computed them, the screenshot
/// shows them, and the state is the records' end.
#[test]
fn view_draws_the_programmed_and_executed_path() {
    let program = program();
    let served = Served::start(&["view", &program, "--port", "0"]);
    let started = Instant::now();
    let url = format!("{}{CANVAS}", served.url);
    let figures = dom_figures(&chromium(&url, &["--dump-dom"]));
    println!(
        "  DOM in {:.1} s, page ready {} ms after its script started",
        started.elapsed().as_secs_f64(),
        figures["load-ms"]
    );
    check_drawn(&figures, &served.figures);
    assert_eq!(figures.get("live-done").map(String::as_str), Some("true"));
    assert_eq!(number(&figures, "live-period"), served.figures["periods"].as_f64().unwrap());
    let shot = out_dir().join("view.png");
    let _ = std::fs::remove_file(&shot);
    chromium(&url, &[&format!("--screenshot={}", shot.display())]);
    check_screenshot(&shot, &figures, false);
}

/// `finestep run --fast --view --pace 0.25` (29 s: a loaded machine's Chromium took 9 s
/// to show the page): the server's state advances during the run, the
/// page loaded mid-run shows it running, and the page loaded after it shows the end the
/// CLI printed, with the positions read back on the way; its screenshot is kept as
/// `target/view/run.png`.
#[test]
fn run_view_follows_the_run_live() {
    let program = program();
    let out = out_dir().join("run");
    let mut served = Served::start(&[
        "run",
        &program,
        "--fast",
        "--view",
        "--port",
        "0",
        "--pace",
        "0.25",
        "--out",
        &out.display().to_string(),
    ]);
    let periods = served.figures["periods"].as_u64().unwrap();
    // The server's state, polled every 100 ms from now to the end of the run.
    let addr = served.addr();
    let poller = std::thread::spawn(move || {
        let mut seen = Vec::new();
        let until = Instant::now() + Duration::from_secs(120);
        while Instant::now() < until {
            let state: serde_json::Value = serde_json::from_str(&get(&addr, "/state.json?since=0")).unwrap();
            if state["done"].as_bool().unwrap() {
                break;
            }
            seen.push(state["period"].as_u64().unwrap());
            std::thread::sleep(Duration::from_millis(100));
        }
        seen
    });
    // The page while the run goes on.
    let during = dom_figures(&chromium(&served.url, &["--dump-dom"]));
    check_drawn(&during, &served.figures);
    let first = number(&during, "first-live-period");
    assert!(first < periods as f64, "the page first saw period {first} of {periods}: not during the run");
    // The server's state advanced.
    let seen = poller.join().unwrap();
    assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{seen:?}");
    assert!(seen.iter().collect::<std::collections::BTreeSet<_>>().len() >= 3, "the state did not advance: {seen:?}");
    // The end as the CLI printed it, on the page.
    let end: serde_json::Value = serde_json::from_str(&served.wait_for("view-final ")).unwrap();
    assert_eq!(end["period"].as_u64(), Some(periods));
    assert_eq!(end["errors"].as_u64(), Some(0));
    let url = format!("{}{CANVAS}", served.url);
    let after = dom_figures(&chromium(&url, &["--dump-dom"]));
    check_drawn(&after, &served.figures);
    let shot = out_dir().join("run.png");
    let _ = std::fs::remove_file(&shot);
    chromium(&url, &[&format!("--screenshot={}", shot.display())]);
    check_screenshot(&shot, &after, true);
    assert_eq!(after.get("live-done").map(String::as_str), Some("true"), "{after:?}");
    assert_eq!(number(&after, "live-period"), periods as f64);
    let (page, cli) = (json(&after, "live-position"), &end["position"]);
    for axis in 0..3 {
        let (p, c) = (page[axis].as_f64().unwrap(), cli[axis].as_f64().unwrap());
        assert!((p - c).abs() < 1e-9, "position {axis}: page {p}, CLI {c}");
    }
    let trail = number(&after, "trail-points");
    assert!(trail >= 10.0, "only {trail} positions read back during the run");
    println!(
        "  mid-run page at period {first} of {periods}; {} server states polled, periods {:?} to {:?}; {trail} read-back points",
        seen.len(),
        seen.first(),
        seen.last()
    );
}
