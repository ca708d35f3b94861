//! `finestep view FILE.ngc` and `finestep run --view`: the programmed and the executed
//! toolpath in 3-D in a browser, served by a small HTTP server bound to 127.0.0.1
//! ([docs/view.md](../../../docs/view.md)).
//!
//! Nothing here reads G-code or records on its own: the programmed path is the planner's
//! path elements ([`finestep_planner::geometry::elements`], after cutter compensation, as
//! `finestep run` plans them), the executed path is the independent checker's positions
//! at every period boundary, rebuilt from the period records
//! ([`finestep_planner::checker::Sample`]), and during a run the live state is what the
//! run reads back from the chip (positions, FIFO level, underruns). The page (`web/`)
//! draws them with three.js, installed by `make setup` (`npm ci` in `web/`).

use std::net::SocketAddr;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;

use anyhow::{anyhow, bail, Context};
use finestep_gcode::{BlockKind, Program};
use finestep_planner::checker::Sample;
use finestep_planner::config::Resolved;
use finestep_planner::cutter_comp::compensate;
use finestep_planner::geometry::elements;
use finestep_planner::{MachineConfig, PlannedProgram};
use serde::Serialize;

/// At most this many points of the executed path go to the page (evenly spaced periods,
/// the last always kept); every period of short programs.
const EXECUTED_POINTS_MAX: usize = 200_000;
/// At most this many points of the programmed path.
const PROGRAMMED_POINTS_MAX: usize = 200_000;
/// Curved elements are drawn with chords of at most this share of the whole path's length.
const CHORD_SHARE: f64 = 1.0 / 2000.0;

/// Where the page's files are: `FINESTEP_WEB` or the checkout's `web/`.
pub fn web_dir() -> PathBuf {
    std::env::var_os("FINESTEP_WEB")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web"))
}

/// A polyline with a feed (units/s) and a time (period index) per point.
#[derive(Serialize, Default, Debug, Clone)]
pub struct Polyline {
    /// x, y, z of each point, mm.
    pub points: Vec<f32>,
    /// Feed at each point, units/s: programmed (the element's speed cap: the programmed
    /// feed within the machine's limits) or executed (the path speed over the period).
    pub feed: Vec<f32>,
    /// The period boundary of each point (executed), or the element's source line
    /// (programmed).
    pub tag: Vec<u64>,
}

impl Polyline {
    fn push(&mut self, p: [f64; 4], feed: f64, tag: u64) {
        self.points.extend([p[0] as f32, p[1] as f32, p[2] as f32]);
        self.feed.push(feed as f32);
        self.tag.push(tag);
    }

    /// Line segments drawn between consecutive points.
    pub fn segments(&self) -> usize {
        (self.points.len() / 3).saturating_sub(1)
    }
}

/// What the page draws, computed once from the plan and the records.
#[derive(Serialize, Debug, Clone)]
pub struct Scene {
    /// The program's name.
    pub name: String,
    /// The period, s.
    pub period_s: f64,
    /// Periods (records) in the program.
    pub periods: u64,
    /// The planner's path (X, Y, Z), tagged with source lines.
    pub programmed: Polyline,
    /// The commanded positions at the period boundaries, from the records.
    pub executed: Polyline,
    /// The source line at each executed point.
    pub executed_lines: Vec<u32>,
    /// Smallest and largest x, y, z over both paths, mm.
    pub bbox: [[f64; 3]; 2],
    /// The colour scale's top, units/s: the fastest programmed feed (G1/G2/G3/G5.2).
    pub feed_max: f64,
}

impl Scene {
    /// The scene of `planned` (planned from `program` on `config`, resolved as
    /// `resolved`) with the checker's `samples` of its records.
    pub fn new(
        name: &str,
        program: &Program,
        config: &MachineConfig,
        resolved: &Resolved,
        planned: &PlannedProgram,
        samples: &[Sample],
    ) -> anyhow::Result<Scene> {
        let compensated = compensate(program, &config.tool_table()).map_err(|e| anyhow!("{name}:{}", e))?;
        let path = elements(resolved, &compensated).map_err(|e| anyhow!("{name}:{}: {}", e.line, e.reason))?;
        let total: f64 = path.elements.iter().map(|e| e.length).sum();
        let chord = (total * CHORD_SHARE).max(1e-6);
        let mut programmed = Polyline::default();
        if let Some(first) = path.elements.first() {
            programmed.push(first.start, first.v_cap, first.line as u64);
        }
        for e in &path.elements {
            let pieces = match e.shape {
                finestep_planner::element::Shape::Line { .. } => 1,
                _ => ((e.length / chord).ceil() as usize).clamp(1, 512),
            };
            for i in 1..=pieces {
                programmed.push(e.position(e.length * i as f64 / pieces as f64), e.v_cap, e.line as u64);
            }
        }
        if programmed.points.len() / 3 > PROGRAMMED_POINTS_MAX {
            programmed = thin(&programmed, PROGRAMMED_POINTS_MAX);
        }

        // The machine at rest at the origin before the first record, then every boundary.
        let mut executed = Polyline::default();
        let mut executed_lines = Vec::new();
        let stride = samples.len().div_ceil(EXECUTED_POINTS_MAX).max(1);
        executed.push([0.0; 4], 0.0, 0);
        executed_lines.push(planned.lines.first().copied().unwrap_or(0) as u32);
        for (i, s) in samples.iter().enumerate() {
            if (i + 1) % stride == 0 || i + 1 == samples.len() {
                executed.push(s.position, s.speed, i as u64 + 1);
                executed_lines.push(planned.lines.get(i).copied().unwrap_or(0) as u32);
            }
        }
        let mut bbox = [[f64::MAX; 3], [f64::MIN; 3]];
        for chunk in programmed.points.chunks(3).chain(executed.points.chunks(3)) {
            for a in 0..3 {
                bbox[0][a] = bbox[0][a].min(f64::from(chunk[a]));
                bbox[1][a] = bbox[1][a].max(f64::from(chunk[a]));
            }
        }
        // The colour scale tops at the fastest programmed feed (rapids, faster, at its
        // top), or at the fastest speed of a program of rapids alone.
        let programmed_feed = compensated
            .blocks
            .iter()
            .filter_map(|b| match b.kind {
                BlockKind::Linear { feed_mm_per_min, .. }
                | BlockKind::Arc { feed_mm_per_min, .. }
                | BlockKind::Nurbs { feed_mm_per_min, .. } => Some(feed_mm_per_min / 60.0),
                _ => None,
            })
            .fold(0.0f64, f64::max);
        let fastest = programmed.feed.iter().chain(&executed.feed).fold(0.0f64, |m, &f| m.max(f64::from(f)));
        let feed_max = if programmed_feed > 0.0 { programmed_feed } else { fastest };
        Ok(Scene {
            name: name.to_string(),
            period_s: resolved.period_s,
            periods: planned.records.len() as u64,
            programmed,
            executed,
            executed_lines,
            bbox,
            feed_max,
        })
    }

    /// The figures the browser test compares the page's with.
    pub fn figures(&self) -> serde_json::Value {
        serde_json::json!({
            "programmed_segments": self.programmed.segments(),
            "executed_segments": self.executed.segments(),
            "bbox": self.bbox,
            "periods": self.periods,
        })
    }
}

/// At most `max` points of `line`, evenly spaced, the last kept.
fn thin(line: &Polyline, max: usize) -> Polyline {
    let n = line.points.len() / 3;
    let stride = n.div_ceil(max).max(1);
    let mut out = Polyline::default();
    for i in (0..n).filter(|i| i % stride == 0 || i + 1 == n) {
        out.points.extend_from_slice(&line.points[3 * i..3 * i + 3]);
        out.feed.push(line.feed[i]);
        out.tag.push(line.tag[i]);
    }
    out
}

/// What a run shows live: where the machine is, how far the run is, the chip's FIFO.
#[derive(Serialize, Debug, Clone, Default)]
pub struct LiveState {
    /// What runs the periods (the chip, or the model's fast path).
    pub source: String,
    /// A run is going on.
    pub running: bool,
    /// The run has ended (or there is no run: `finestep view`).
    pub done: bool,
    /// Periods in the program.
    pub periods: u64,
    /// Periods run so far (the chip's: read back).
    pub period: u64,
    /// Records queued into the chip so far.
    pub queued: u64,
    /// The position read back, x, y, z in mm.
    pub position: [f64; 3],
    /// Records in the chip's FIFO and its room left, when read.
    pub fifo: Option<[u32; 2]>,
    /// FIFO underruns the chip counted in this run.
    pub underruns: u64,
    /// What went wrong.
    pub errors: Vec<String>,
    /// Every position read back during the run: x, y, z (mm) and the period.
    #[serde(skip)]
    pub trail: Vec<[f64; 4]>,
}

/// The live state shared between a run and the server.
#[derive(Clone, Default)]
pub struct Live(Arc<Mutex<LiveState>>);

impl Live {
    /// The state, to read or update (a panicked holder's state is used as it is).
    pub fn lock(&self) -> MutexGuard<'_, LiveState> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The state as JSON, with the trail from point `since` on.
    fn json(&self, since: usize) -> String {
        let state = self.lock();
        let trail: Vec<[f64; 4]> = state.trail.iter().skip(since).copied().collect();
        let mut value = serde_json::to_value(&*state).unwrap_or_default();
        if let Some(map) = value.as_object_mut() {
            map.insert("trail_from".into(), since.min(state.trail.len()).into());
            map.insert("trail".into(), serde_json::to_value(trail).unwrap_or_default());
        }
        value.to_string()
    }
}

/// The view's server: runs until the process ends or [`Server::stop`].
pub struct Server {
    /// The address it listens on (127.0.0.1, port as asked or chosen).
    pub addr: SocketAddr,
    #[cfg_attr(not(test), allow(dead_code))] // stopped by the tests; the CLI serves until it ends
    server: Arc<tiny_http::Server>,
    thread: Option<JoinHandle<()>>,
}

impl Server {
    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Serves until the process ends.
    pub fn wait(mut self) {
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }

    /// Stops serving.
    #[cfg_attr(not(test), allow(dead_code))]
    pub fn stop(mut self) {
        self.server.unblock();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// Checks that the page and three.js are in `web` (a clear error, not a blank page).
fn check_web(web: &Path) -> anyhow::Result<()> {
    for file in ["index.html", "view.js"] {
        if !web.join(file).is_file() {
            bail!("the view's page {} is missing (FINESTEP_WEB or the checkout's web/)", web.join(file).display());
        }
    }
    let three = web.join("node_modules/three/build/three.module.js");
    if !three.is_file() {
        bail!("three.js is not installed ({} missing): run `make setup` (npm ci in web/)", three.display());
    }
    Ok(())
}

/// Serves `scene` and `live` on 127.0.0.1:`port` (0: a free port) with the page in `web`.
pub fn serve(port: u16, web: &Path, scene: &Scene, live: Live) -> anyhow::Result<Server> {
    check_web(web)?;
    let scene_json = Arc::new(serde_json::to_string(scene)?);
    let server = tiny_http::Server::http(("127.0.0.1", port))
        .map_err(|e| anyhow!("view: cannot listen on 127.0.0.1:{port}: {e}"))?;
    let addr = server.server_addr().to_ip().context("view: the server has no IP address")?;
    let server = Arc::new(server);
    let web = web.to_path_buf();
    let thread = {
        let server = Arc::clone(&server);
        std::thread::spawn(move || {
            for request in server.incoming_requests() {
                let _ = answer(request, &web, &scene_json, &live);
            }
        })
    };
    Ok(Server { addr, server, thread: Some(thread) })
}

fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("json") => "application/json",
        _ => "application/octet-stream",
    }
}

fn header(name: &str, value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("a valid header")
}

fn answer(mut request: tiny_http::Request, web: &Path, scene: &str, live: &Live) -> std::io::Result<()> {
    let _ = request.as_reader().read_to_end(&mut Vec::new());
    let url = request.url().to_string();
    let (path, query) = url.split_once('?').unwrap_or((&url, ""));
    let json = |body: String| {
        tiny_http::Response::from_string(body)
            .with_header(header("Content-Type", "application/json"))
            .with_header(header("Cache-Control", "no-store"))
    };
    match path {
        "/scene.json" => request.respond(json(scene.to_string())),
        "/state.json" => {
            let since = query
                .split('&')
                .find_map(|kv| kv.strip_prefix("since="))
                .and_then(|v| v.parse::<usize>().ok())
                .unwrap_or(0);
            request.respond(json(live.json(since)))
        }
        _ => {
            // The page's files, and three.js's build and add-ons from node_modules.
            let relative = match path {
                "/" => "index.html".to_string(),
                p if p.starts_with("/three/build/") || p.starts_with("/three/examples/jsm/") => {
                    format!("node_modules{p}")
                }
                p => p.trim_start_matches('/').to_string(),
            };
            let file = Path::new(&relative);
            let safe = file.components().all(|c| matches!(c, Component::Normal(_)));
            let bytes = if safe && !relative.is_empty() { std::fs::read(web.join(file)).ok() } else { None };
            match bytes {
                Some(bytes) => request.respond(
                    tiny_http::Response::from_data(bytes).with_header(header("Content-Type", content_type(file))),
                ),
                _ => request.respond(tiny_http::Response::from_string("not found").with_status_code(404)),
            }
        }
    }
}

/// `finestep view FILE.ngc`: plans the program as `finestep run --fast` does, checks it,
/// and serves the view of its programmed path and its records until the process ends.
pub fn view(
    file: &Path,
    config_path: Option<&Path>,
    profile: Option<&str>,
    port: u16,
    web: Option<&Path>,
) -> anyhow::Result<()> {
    let (mut config, config_name) = crate::config_file::load_or_builtin(config_path)?;
    crate::config_file::set_profile(&mut config, profile);
    let program = finestep_gcode::parse_file(file)?;
    let name = file.display().to_string();
    let (config, resolved) = crate::machine_setup::resolve(config, crate::machine_setup::model_limits(), &config_name)?;
    let planned =
        finestep_planner::plan_program(&config, &program).map_err(|e| anyhow!("{name}:{}: {}", e.line, e.reason))?;
    let report = finestep_planner::check_program(&config, &program, &planned.records)?;
    let scene = Scene::new(&name, &program, &config, &resolved, &planned, &report.samples)?;
    let live = Live::default();
    {
        let mut state = live.lock();
        state.source = "the period records (no run)".into();
        state.done = true;
        state.periods = scene.periods;
        state.period = scene.periods;
        let end = report.samples.last().map_or([0.0; 4], |s| s.position);
        state.position = [end[0], end[1], end[2]];
        if !report.passed() {
            state.errors.push(format!("the checker found {} violations", report.violation_count));
        }
    }
    let web = web.map_or_else(web_dir, Path::to_path_buf);
    let server = serve(port, &web, &scene, live)?;
    println!("finestep view {name}: {} periods, {} path elements", scene.periods, planned.elements);
    println!("view-figures {}", scene.figures());
    println!("view: {} (Ctrl-C ends)", server.url());
    server.wait();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};

    fn get(addr: SocketAddr, path: &str) -> String {
        let mut stream = std::net::TcpStream::connect(addr).unwrap();
        write!(stream, "GET {path} HTTP/1.0\r\nHost: x\r\n\r\n").unwrap();
        let mut text = String::new();
        stream.read_to_string(&mut text).unwrap();
        text
    }

    fn scene_of(text: &str) -> Scene {
        let program = finestep_gcode::parse_str(text, "t.ngc").unwrap();
        let (config, resolved) =
            crate::machine_setup::resolve(MachineConfig::default(), crate::machine_setup::model_limits(), "<built-in>")
                .unwrap();
        let planned = finestep_planner::plan_program(&config, &program).unwrap();
        let report = finestep_planner::check_program(&config, &program, &planned.records).unwrap();
        Scene::new("t.ngc", &program, &config, &resolved, &planned, &report.samples).unwrap()
    }

    /// The scene of a square with an arc: both paths from the origin to the end, the box
    /// the square's, one executed point per period.
    #[test]
    fn scene_holds_both_paths() {
        let scene = scene_of("G1 X10 F600\nG1 Y10\nG3 X0 Y10 I-5 J0\nG1 Y0 Z-2\nM2\n");
        assert_eq!(scene.executed.segments() as u64, scene.periods);
        assert!(scene.programmed.segments() > 4, "{}", scene.programmed.segments());
        assert_eq!(&scene.programmed.points[..3], &[0.0, 0.0, 0.0]);
        let n = scene.programmed.points.len();
        assert_eq!(&scene.programmed.points[n - 3..], &[0.0, 0.0, -2.0]);
        assert!((scene.bbox[1][0] - 10.0).abs() < 1e-3 && (scene.bbox[1][1] - 15.0).abs() < 1e-2, "{:?}", scene.bbox);
        assert!((scene.bbox[0][2] + 2.0).abs() < 1e-3);
        assert!((scene.feed_max - 10.0).abs() < 1e-6, "{}", scene.feed_max);
        let rapid = scene_of("G0 X5\nG1 X10 F300\nM2\n");
        assert!((rapid.feed_max - 5.0).abs() < 1e-6, "{}", rapid.feed_max);
    }

    /// The server answers the scene, the state, the page and three.js, and refuses paths
    /// outside its directory.
    #[test]
    fn server_answers_and_refuses() {
        let web = std::env::temp_dir().join(format!("finestep-view-test-{}", std::process::id()));
        std::fs::create_dir_all(web.join("node_modules/three/build")).unwrap();
        std::fs::write(web.join("index.html"), "<p>page</p>").unwrap();
        std::fs::write(web.join("view.js"), "// js").unwrap();
        std::fs::write(web.join("node_modules/three/build/three.module.js"), "// three").unwrap();
        let scene = scene_of("G1 X1 F600\nM2\n");
        let live = Live::default();
        live.lock().trail = vec![[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]];
        let server = serve(0, &web, &scene, live).unwrap();
        assert!(get(server.addr, "/").contains("<p>page</p>"));
        assert!(get(server.addr, "/three/build/three.module.js").contains("// three"));
        assert!(get(server.addr, "/scene.json").contains("\"programmed\""));
        let state = get(server.addr, "/state.json?since=1");
        assert!(state.contains("\"trail\":[[5.0,6.0,7.0,8.0]]"), "{state}");
        assert!(get(server.addr, "/../Cargo.toml").starts_with("HTTP/1.0 404"));
        assert!(get(server.addr, "/three/build/../../../../index.html").contains(" 404"));
        server.stop();
        std::fs::remove_dir_all(&web).unwrap();
    }

    /// Without three.js installed the view says what to run.
    #[test]
    fn missing_three_is_a_clear_error() {
        let web = std::env::temp_dir().join(format!("finestep-view-none-{}", std::process::id()));
        std::fs::create_dir_all(&web).unwrap();
        std::fs::write(web.join("index.html"), "").unwrap();
        std::fs::write(web.join("view.js"), "").unwrap();
        let error = serve(0, &web, &scene_of("G1 X1 F600\nM2\n"), Live::default()).err().unwrap().to_string();
        assert!(error.contains("make setup"), "{error}");
        std::fs::remove_dir_all(&web).unwrap();
    }
}
