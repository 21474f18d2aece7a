//! A live view of a device in a local web page (`fricctl device view`).
//!
//! One thread owns the link to the device ([`Client`]) and does everything
//! that talks to it, one request at a time: it keeps a stream of estimates
//! running (or, while the closed μ loop runs, reads the loop's updates),
//! polls the status and the drive setting every [`Config::status_every`],
//! runs the page's controls between two polls, and every
//! [`Config::batch_every`] publishes what it read as one JSON batch on a
//! bounded broadcast channel ([`BROADCAST_BATCHES`]). An HTTP server (axum on
//! tokio) serves the page, its script and the vendored plotting library
//! (uPlot, compiled into the binary: the page works offline), and one
//! WebSocket per page that forwards the batches. A page that reads too
//! slowly loses batches (it is told how many); it never holds back the
//! device thread or another page.
//!
//! The controls are the CLI's commands: the page sends the words of a
//! `fricctl device …` command (`start`, `drive set --freq … --phase-deg 30`,
//! `control --target-mu 0.1 --v0 0.004`), and [`Controls::run`] — given by
//! the front end — parses and runs them as the CLI does, so a refusal is the
//! CLI's one line, shown on the page.
//!
//! Every row published (and recorded, `--record`) has the CLI's JSON keys
//! ([`COLUMNS`]); `t_s` is the host's time since the view started, s.

use std::collections::VecDeque;
use std::io::Write;
use std::net::TcpListener;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response as HttpResponse};
use axum::routing::{get, post};
use axum::{Json, Router};
use board::protocol::{Request, Response, StreamEnd, Telemetry};
use serde_json::{json, Map, Value};
use tokio::sync::{broadcast, oneshot};

use crate::answers::{expect, f32v};
use crate::client::Client;
use crate::names::fault_names;
use crate::report;
use crate::{Error, Result};

/// The page.
const PAGE_HTML: &str = include_str!("../assets/view/index.html");
/// The page's script (plain JS, no framework).
const PAGE_JS: &str = include_str!("../assets/view/view.js");
/// uPlot 1.6.32 (MIT, `assets/uplot/LICENSE`), from the npm registry.
const UPLOT_JS: &str = include_str!("../assets/uplot/uPlot.iife.min.js");
/// uPlot's style sheet.
const UPLOT_CSS: &str = include_str!("../assets/uplot/uPlot.min.css");

/// Batches the broadcast channel holds for a page that reads slowly; a page
/// further behind skips to the newest (at 10 batches a second: 6.4 s).
pub const BROADCAST_BATCHES: usize = 64;
/// Batches kept for a page that opens later, so that its plots start with
/// the last seconds (at 10 a second: 30 s) …
pub const HISTORY_BATCHES: usize = 300;
/// … and at most this many bytes of them (at a stream's full rate, 625
/// estimates a second, 30 s of batches are ≈ 3 MB).
pub const HISTORY_BYTES: usize = 4 << 20;
/// Estimates (or loop updates) in one batch at most: at a stream's full
/// rate (an estimate every 32 periods, 625 a second at 20 kHz) a batch has
/// ≈ 63, and this leaves 3 s for a device thread that fell behind (a loaded
/// machine) to catch up; beyond, the page gets the newest ones (the count
/// dropped is in the batch, `dropped_rows`); `--record` writes them all.
pub const MAX_ROWS_PER_BATCH: usize = 2000;

/// The columns of a row, in the CSV's order: the CLI's JSON keys (`device
/// status`, `drive get`, `measure`, `control status`; docs/device-json.md)
/// plus `t_s` (s since the view started), `kind` (`estimate`, `status` or
/// `control`) and `liftoff_limit_m` (the setting's lift-off guard
/// (1 − margin)·u_z0, m).
pub const COLUMNS: [&str; 30] = [
    "t_s",
    "kind",
    "mu",
    "std_error",
    "valid",
    "reasons",
    "periods",
    "target_mu",
    "measured_mu",
    "freq",
    "duz",
    "dux",
    "uz0",
    "phi_deg",
    "amp_z_measured_m",
    "amp_x_measured_m",
    "phase_measured_deg",
    "amp_z_peak_m",
    "liftoff_limit_m",
    "frequency_hz",
    "tracking_error_hz",
    "locked",
    "track",
    "headroom",
    "running",
    "settled",
    "drive_mode",
    "faults",
    "cpu_load_pct",
    "cpu_load_max_pct",
];

/// How the view runs.
#[derive(Debug, Clone)]
pub struct Config {
    /// The page's controls are refused (`--read-only`, for demonstrations).
    pub read_only: bool,
    /// Drive periods per streamed estimate; `None`: a tenth of a second's
    /// worth at the drive frequency in force (at least 32), so that the μ
    /// plot moves ten times a second.
    pub periods: Option<u32>,
    /// Every row also to this CSV file ([`COLUMNS`]), each row written and
    /// flushed whole; the caller applied the overwrite policy.
    pub record: Option<PathBuf>,
    /// How often the status and drive are polled.
    pub status_every: Duration,
    /// How often a batch goes to the pages.
    pub batch_every: Duration,
    /// What answered (the link's description), shown on the page.
    pub link: String,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            read_only: false,
            periods: None,
            record: None,
            status_every: Duration::from_millis(100),
            batch_every: Duration::from_millis(100),
            link: String::new(),
        }
    }
}

/// The front end's commands: the page's controls go through them.
pub trait Controls: Send + 'static {
    /// Runs the `fricctl device` command `words` (without `fricctl device`)
    /// on the open device, as the CLI does; its text on success.
    ///
    /// # Errors
    /// The CLI's one line: a bad flag, a command the view does not offer,
    /// the device's refusal.
    fn run(&mut self, c: &mut Client, words: &[String]) -> Result<String>;
}

/// A control from a page, with where its answer goes.
struct Action {
    words: Vec<String>,
    reply: oneshot::Sender<std::result::Result<String, String>>,
}

/// What the server's handlers share.
#[derive(Clone)]
struct Shared {
    batches: broadcast::Sender<Utf8Bytes>,
    history: Arc<Mutex<VecDeque<Utf8Bytes>>>,
    hello: Utf8Bytes,
    actions: mpsc::Sender<Action>,
    read_only: bool,
}

/// Serves the view on `listener` until `stop` is set (Ctrl-C) or the device
/// thread ends; the stream is stopped on the device before returning.
///
/// # Errors
/// The record file cannot be created, the server cannot start, or the
/// device failed (its one line).
pub fn serve(
    client: Client,
    listener: TcpListener,
    cfg: Config,
    controls: Box<dyn Controls>,
    stop: Arc<AtomicBool>,
) -> Result<()> {
    let record = match &cfg.record {
        Some(p) => Some(Recorder::create(p)?),
        None => None,
    };
    let (batches, _) = broadcast::channel(BROADCAST_BATCHES);
    let history = Arc::new(Mutex::new(VecDeque::new()));
    let (actions, inbox) = mpsc::channel();
    let hello = json!({
        "type": "hello",
        "columns": COLUMNS,
        "read_only": cfg.read_only,
        "link": cfg.link,
        "record": cfg.record.as_ref().map(|p| p.display().to_string()),
    });
    let shared = Shared {
        batches: batches.clone(),
        history: history.clone(),
        hello: hello.to_string().into(),
        actions,
        read_only: cfg.read_only,
    };
    let device_stop = stop.clone();
    let device = std::thread::spawn(move || {
        let mut d = DeviceThread::new(client, cfg, controls, record, batches, history);
        let r = d.run(&inbox, &device_stop);
        device_stop.store(true, Ordering::SeqCst);
        r
    });
    listener
        .set_nonblocking(true)
        .map_err(|e| Error::failure(format!("--listen: {e}")))?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| Error::failure(format!("the view's server: {e}")))?;
    let server_stop = stop.clone();
    let served: Result<()> = rt.block_on(async move {
        let l = tokio::net::TcpListener::from_std(listener)
            .map_err(|e| Error::failure(format!("--listen: {e}")))?;
        let app = router(shared);
        tokio::select! {
            r = async { axum::serve(l, app).await } => {
                r.map_err(|e| Error::failure(format!("the view's server: {e}")))
            }
            () = stopped(server_stop) => Ok(()),
        }
    });
    // Open WebSockets do not hold the process.
    rt.shutdown_timeout(Duration::from_millis(200));
    stop.store(true, Ordering::SeqCst);
    let device = device
        .join()
        .unwrap_or_else(|_| Err(Error::failure("the view's device thread failed")));
    served.and(device)
}

/// Resolves once `stop` is set.
async fn stopped(stop: Arc<AtomicBool>) {
    while !stop.load(Ordering::SeqCst) {
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

fn router(shared: Shared) -> Router {
    let text = |ty: &'static str, body: &'static str| {
        move || async move { ([(header::CONTENT_TYPE, ty)], body) }
    };
    Router::new()
        .route("/", get(text("text/html; charset=utf-8", PAGE_HTML)))
        .route(
            "/view.js",
            get(text("text/javascript; charset=utf-8", PAGE_JS)),
        )
        .route(
            "/uPlot.iife.min.js",
            get(text("text/javascript; charset=utf-8", UPLOT_JS)),
        )
        .route(
            "/uPlot.min.css",
            get(text("text/css; charset=utf-8", UPLOT_CSS)),
        )
        .route("/ws", get(ws_upgrade))
        .route("/api/action", post(action))
        .with_state(shared)
}

async fn ws_upgrade(ws: WebSocketUpgrade, State(sh): State<Shared>) -> HttpResponse {
    ws.on_upgrade(move |socket| page(socket, sh))
}

/// One page: the hello, the recent batches, then every batch as it comes
/// (a page behind by more than [`BROADCAST_BATCHES`] is told how many it
/// lost and goes on from the newest).
async fn page(mut ws: WebSocket, sh: Shared) {
    // Subscribed under the history's lock, under which every batch is also
    // kept and sent: each batch comes once, from the history or the channel.
    let (mut rx, recent): (_, Vec<Utf8Bytes>) = match sh.history.lock() {
        Ok(h) => (sh.batches.subscribe(), h.iter().cloned().collect()),
        Err(_) => (sh.batches.subscribe(), Vec::new()),
    };
    for m in std::iter::once(sh.hello.clone()).chain(recent) {
        if ws.send(Message::Text(m)).await.is_err() {
            return;
        }
    }
    loop {
        tokio::select! {
            b = rx.recv() => {
                let m = match b {
                    Ok(m) => m,
                    Err(broadcast::error::RecvError::Lagged(n)) => {
                        json!({"type": "lagged", "batches": n}).to_string().into()
                    }
                    Err(broadcast::error::RecvError::Closed) => break,
                };
                if ws.send(Message::Text(m)).await.is_err() {
                    break;
                }
            }
            m = ws.recv() => match m {
                None | Some(Err(_)) | Some(Ok(Message::Close(_))) => break,
                Some(Ok(_)) => {}
            },
        }
    }
}

/// The body of `POST /api/action`.
#[derive(serde::Deserialize)]
struct ActionBody {
    words: Vec<String>,
}

/// `POST /api/action {"words": [...]}`: the command through the device
/// thread; `{"ok", "message", "command"}` (403 in a read-only view, 422 for
/// a refusal).
async fn action(State(sh): State<Shared>, Json(body): Json<ActionBody>) -> HttpResponse {
    let command = format!("fricctl device {}", body.words.join(" "));
    let answer = |status: StatusCode, ok: bool, message: String| {
        (
            status,
            Json(json!({"ok": ok, "message": message, "command": command})),
        )
            .into_response()
    };
    if sh.read_only {
        return answer(
            StatusCode::FORBIDDEN,
            false,
            "read-only view (--read-only): the controls are off".to_string(),
        );
    }
    let (reply, answered) = oneshot::channel();
    let sent = sh.actions.send(Action {
        words: body.words,
        reply,
    });
    if sent.is_err() {
        return answer(
            StatusCode::SERVICE_UNAVAILABLE,
            false,
            "the device thread has stopped".to_string(),
        );
    }
    match tokio::time::timeout(Duration::from_secs(120), answered).await {
        Ok(Ok(Ok(text))) => answer(StatusCode::OK, true, text),
        Ok(Ok(Err(msg))) => answer(StatusCode::UNPROCESSABLE_ENTITY, false, msg),
        _ => answer(
            StatusCode::GATEWAY_TIMEOUT,
            false,
            "no answer from the device thread within 120 s".to_string(),
        ),
    }
}

/// `--record FILE`: the CSV, each row written and flushed whole.
struct Recorder {
    file: std::fs::File,
    path: PathBuf,
}

impl Recorder {
    fn create(p: &std::path::Path) -> Result<Self> {
        let fail = |e: std::io::Error| Error::failure(format!("--record: {}: {e}", p.display()));
        let mut file = std::fs::File::create(p).map_err(fail)?;
        file.write_all(format!("{}\n", COLUMNS.join(",")).as_bytes())
            .and_then(|()| file.flush())
            .map_err(fail)?;
        Ok(Recorder {
            file,
            path: p.to_path_buf(),
        })
    }

    fn write(&mut self, row: &Map<String, Value>) -> Result<()> {
        let line = csv_line(row);
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| Error::failure(format!("--record: {}: {e}", self.path.display())))
    }
}

/// One CSV line of a row in [`COLUMNS`] order: numbers as JSON writes them,
/// booleans `true`/`false`, lists of names joined by spaces, absent values
/// empty.
pub fn csv_line(row: &Map<String, Value>) -> String {
    let cell = |v: Option<&Value>| match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(Value::Array(a)) => a
            .iter()
            .map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string))
            .collect::<Vec<_>>()
            .join(" "),
        Some(v) => v.to_string(),
    };
    let mut s = COLUMNS
        .iter()
        .map(|k| cell(row.get(*k)))
        .collect::<Vec<_>>()
        .join(",");
    s.push('\n');
    s
}

/// The thread that owns the link.
struct DeviceThread {
    c: Client,
    cfg: Config,
    controls: Box<dyn Controls>,
    record: Option<Recorder>,
    batches: broadcast::Sender<Utf8Bytes>,
    history: Arc<Mutex<VecDeque<Utf8Bytes>>>,
    /// The bytes of the batches in `history`.
    history_bytes: usize,
    t0: Instant,
    /// Rows not yet published: estimates and control updates, status.
    fast: VecDeque<Map<String, Value>>,
    slow: Vec<Map<String, Value>>,
    dropped_rows: u64,
    events: Vec<Value>,
    /// The device's state for the page (running, faults, identification …).
    state: Map<String, Value>,
    streaming: bool,
    /// The drive runs: estimates are streamed only then (a stream with the
    /// drive stopped measures nothing, and without a preload it saturates
    /// the force ADC, a fault).
    running: bool,
    loop_on: bool,
    faulted: bool,
    liftoff_margin: f64,
    frequency_hz: f64,
}

impl DeviceThread {
    fn new(
        c: Client,
        cfg: Config,
        controls: Box<dyn Controls>,
        record: Option<Recorder>,
        batches: broadcast::Sender<Utf8Bytes>,
        history: Arc<Mutex<VecDeque<Utf8Bytes>>>,
    ) -> Self {
        DeviceThread {
            c,
            cfg,
            controls,
            record,
            batches,
            history,
            history_bytes: 0,
            t0: Instant::now(),
            fast: VecDeque::new(),
            slow: Vec::new(),
            dropped_rows: 0,
            events: Vec::new(),
            state: Map::new(),
            streaming: false,
            running: false,
            loop_on: false,
            faulted: false,
            liftoff_margin: 0.05,
            frequency_hz: 0.0,
        }
    }

    fn t(&self) -> f64 {
        (self.t0.elapsed().as_secs_f64() * 1e3).round() / 1e3
    }

    /// A line for the page's message area (and stderr).
    fn event(&mut self, text: String) {
        eprintln!("{text}");
        let t = self.t();
        self.events.push(json!({"t_s": t, "text": text}));
    }

    fn run(&mut self, inbox: &mpsc::Receiver<Action>, stop: &AtomicBool) -> Result<()> {
        self.refresh_info()?;
        self.refresh_identification();
        self.refresh_control();
        let mut last_status = Instant::now() - self.cfg.status_every;
        let mut last_batch = Instant::now();
        let mut last_stream_try: Option<Instant> = None;
        let mut failing: Option<String> = None;
        while !stop.load(Ordering::SeqCst) {
            while let Ok(a) = inbox.try_recv() {
                let r = self.act(&a.words);
                let _ = a.reply.send(r.map_err(|e| e.msg));
            }
            let polled = self
                .telemetry()
                .and_then(|()| {
                    if last_status.elapsed() >= self.cfg.status_every {
                        last_status = Instant::now();
                        self.poll_status()
                    } else {
                        Ok(())
                    }
                })
                .and_then(|()| {
                    let due = last_stream_try.is_none_or(|t| t.elapsed() > Duration::from_secs(1));
                    let wanted = self.running && !self.loop_on && !self.faulted;
                    if !self.streaming && wanted && due {
                        last_stream_try = Some(Instant::now());
                        self.start_stream()
                    } else if self.streaming && !self.running {
                        self.stop_stream()
                    } else {
                        Ok(())
                    }
                });
            match polled {
                Ok(()) => failing = None,
                Err(e) => {
                    // The link failed (device gone): said once, tried again each second.
                    if failing.as_deref() != Some(&e.msg) {
                        self.event(format!("device: {}", e.msg));
                        failing = Some(e.msg.clone());
                    }
                    self.state.insert("link_error".into(), e.msg.into());
                    std::thread::sleep(Duration::from_millis(1000));
                }
            }
            if last_batch.elapsed() >= self.cfg.batch_every {
                last_batch = Instant::now();
                self.publish();
            }
        }
        if self.streaming {
            let stopped = self.c.uninterrupted(|c| {
                c.call(Request::Stream {
                    on: false,
                    periods: 1,
                })
            });
            if let Err(e) = stopped.and_then(expect) {
                return Err(Error::failure(format!(
                    "could not stop the stream ({}); `fricctl device reset` ends it",
                    e.msg
                )));
            }
            eprintln!("stream stopped");
        }
        Ok(())
    }

    /// A page's control: the stream is stopped first for `control` (the
    /// loop needs the estimator), then the CLI's command runs.
    fn act(&mut self, words: &[String]) -> Result<String> {
        let command = format!("fricctl device {}", words.join(" "));
        if words.first().map(String::as_str) == Some("control") && self.streaming {
            self.stop_stream()?;
        }
        let r = self.controls.run(&mut self.c, words);
        match &r {
            Ok(_) => self.event(format!("{command}: done")),
            Err(e) => self.event(format!("{command}: {}", e.msg)),
        }
        self.refresh_control();
        self.refresh_identification();
        r
    }

    fn refresh_info(&mut self) -> Result<()> {
        if let Response::Info(i) = expect(self.c.call(Request::Hello)?)? {
            self.liftoff_margin = f64::from(i.liftoff_margin);
            self.state
                .insert("board".into(), report::board_name(&i.board).into());
        }
        Ok(())
    }

    fn refresh_identification(&mut self) {
        let v = match self.c.call(Request::GetTransducers).and_then(expect) {
            Ok(Response::Transducers(Some(t))) => json!({
                "resonance_z_hz": f32v(t.z.resonance_hz),
                "q_z": f32v(t.z.q),
                "resonance_x_hz": f32v(t.x.resonance_hz),
                "q_x": f32v(t.x.q),
            }),
            _ => Value::Null,
        };
        self.state.insert("identified".into(), v);
    }

    fn refresh_control(&mut self) {
        if let Ok(Response::Control(s)) = self.c.call(Request::GetControl).and_then(expect) {
            self.loop_on = s.setting.on;
            self.state.insert(
                "control".into(),
                json!({
                    "on": s.setting.on,
                    "target_mu": f32v(s.setting.target_mu),
                    "v0": f32v(s.setting.v0_m_s),
                }),
            );
        }
    }

    /// The stream off (the drive stopped, or the μ loop needs the estimator).
    fn stop_stream(&mut self) -> Result<()> {
        expect(self.c.call(Request::Stream {
            on: false,
            periods: 1,
        })?)?;
        self.streaming = false;
        Ok(())
    }

    /// The stream on, at [`Config::periods`] or a tenth of a second's worth.
    fn start_stream(&mut self) -> Result<()> {
        let periods = self
            .cfg
            .periods
            .unwrap_or_else(|| ((self.frequency_hz / 10.0).round() as u32).max(32));
        match self.c.call(Request::Stream { on: true, periods })? {
            Response::Ok => {
                // What came before is an earlier session's.
                self.c.discard_telemetry();
                self.streaming = true;
                self.state.insert("periods".into(), periods.into());
            }
            Response::Error(e) => {
                let msg = crate::answers::wire_error(e).msg;
                self.state.insert("stream_error".into(), msg.into());
            }
            _ => {}
        }
        Ok(())
    }

    /// Reads the telemetry that came, for up to 10 ms.
    fn telemetry(&mut self) -> Result<()> {
        let until = Instant::now() + Duration::from_millis(10);
        loop {
            let left = until.saturating_duration_since(Instant::now());
            let Some((_, t)) = self.c.next_telemetry(left)? else {
                return Ok(());
            };
            match t {
                Telemetry::Estimate(e) => {
                    let mut row = report::estimate(&e).json_map();
                    row.retain(|k, _| {
                        matches!(
                            k.as_str(),
                            "mu" | "std_error" | "valid" | "reasons" | "periods"
                        )
                    });
                    self.push_fast("estimate", row);
                }
                Telemetry::Control(u) => {
                    let mut row = report::control_update(&u).json_map();
                    row.insert("mu".into(), f32v(u.measured_mu).into());
                    row.retain(|k, _| {
                        matches!(
                            k.as_str(),
                            "mu" | "std_error" | "target_mu" | "measured_mu" | "duz"
                        )
                    });
                    self.push_fast("control", row);
                }
                Telemetry::Fault(bits) => {
                    self.faulted = true;
                    self.event(format!(
                        "fault latched: {} (drive off)",
                        fault_names(bits).join(", ")
                    ));
                }
                Telemetry::StreamStopped(end) => {
                    self.streaming = false;
                    let why = match end {
                        // The view's own `Stream { on: false }`.
                        StreamEnd::Requested => continue,
                        StreamEnd::Reset => "ended by a device reset".to_string(),
                        StreamEnd::Refused(e) => format!("ended by the device: {e}"),
                    };
                    self.event(format!("stream {why}"));
                }
                Telemetry::RampDone | Telemetry::RxOverflow(_) => {}
            }
        }
    }

    fn push_fast(&mut self, kind: &str, mut row: Map<String, Value>) {
        row.insert("t_s".into(), self.t().into());
        row.insert("kind".into(), kind.into());
        self.record_row(&row);
        if self.fast.len() >= MAX_ROWS_PER_BATCH {
            self.fast.pop_front();
            self.dropped_rows += 1;
        }
        self.fast.push_back(row);
    }

    fn record_row(&mut self, row: &Map<String, Value>) {
        if let Some(r) = &mut self.record {
            if let Err(e) = r.write(row) {
                let msg = e.msg;
                self.record = None;
                self.event(format!("{msg}; recording stopped"));
            }
        }
    }

    /// `GetStatus` and `GetDrive`: one status row, and the state.
    fn poll_status(&mut self) -> Result<()> {
        let Response::Status(st) = expect(self.c.call(Request::GetStatus)?)? else {
            return Ok(());
        };
        let Response::Drive { setting, applied } = expect(self.c.call(Request::GetDrive)?)? else {
            return Ok(());
        };
        self.frequency_hz = f64::from(st.frequency_hz);
        self.running = st.running;
        let was_faulted = self.faulted;
        self.faulted = st.faults != 0;
        if was_faulted && !self.faulted {
            self.event("faults cleared".to_string());
        }
        let mut row = report::status(&st).json_map();
        row.extend(report::drive(&setting, &applied).json_map());
        let guard = (1.0 - self.liftoff_margin) * f64::from(setting.offset_z_m);
        row.insert("liftoff_limit_m".into(), f32v(guard as f32).into());
        row.retain(|k, _| COLUMNS.contains(&k.as_str()));
        row.insert("t_s".into(), self.t().into());
        row.insert("kind".into(), "status".into());
        self.record_row(&row);
        for k in [
            "running",
            "settled",
            "drive_mode",
            "locked",
            "track",
            "headroom",
            "faults",
            "cpu_load_pct",
            "cpu_load_max_pct",
            "freq",
            "duz",
            "dux",
            "uz0",
            "phi_deg",
        ] {
            if let Some(v) = row.get(k) {
                self.state.insert(k.into(), v.clone());
            }
        }
        self.state.remove("link_error");
        self.slow.push(row);
        Ok(())
    }

    /// One batch to every page (and to the history for later pages).
    fn publish(&mut self) {
        let mut state = self.state.clone();
        state.insert("streaming".into(), self.streaming.into());
        state.insert("loop_on".into(), self.loop_on.into());
        state.insert("t_s".into(), self.t().into());
        state.insert(
            "recording".into(),
            self.record
                .as_ref()
                .map(|r| r.path.display().to_string())
                .into(),
        );
        let rows: Vec<Value> = self
            .fast
            .drain(..)
            .chain(self.slow.drain(..))
            .map(Value::Object)
            .collect();
        let batch = json!({
            "type": "batch",
            "rows": rows,
            "state": state,
            "events": std::mem::take(&mut self.events),
            "dropped_rows": std::mem::take(&mut self.dropped_rows),
        });
        let text: Utf8Bytes = batch.to_string().into();
        // Kept and sent under the lock (see `page`); the send never waits.
        let mut h = match self.history.lock() {
            Ok(h) => h,
            Err(poisoned) => poisoned.into_inner(),
        };
        h.push_back(text.clone());
        self.history_bytes += text.len();
        while h.len() > HISTORY_BATCHES || self.history_bytes > HISTORY_BYTES {
            match h.pop_front() {
                Some(old) => self.history_bytes -= old.len(),
                None => break,
            }
        }
        // No page open: nobody to tell.
        let _ = self.batches.send(text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_line_in_column_order() {
        let mut row = Map::new();
        row.insert("t_s".into(), 1.5.into());
        row.insert("kind".into(), "status".into());
        row.insert("faults".into(), json!(["external", "adc_overrun"]));
        row.insert("running".into(), false.into());
        row.insert("amp_z_peak_m".into(), 2e-6.into());
        let line = csv_line(&row);
        let cells: Vec<&str> = line.trim_end().split(',').collect();
        assert_eq!(cells.len(), COLUMNS.len());
        let at = |k: &str| cells[COLUMNS.iter().position(|c| *c == k).unwrap()];
        assert_eq!(at("t_s"), "1.5");
        assert_eq!(at("kind"), "status");
        assert_eq!(at("faults"), "external adc_overrun");
        assert_eq!(at("running"), "false");
        assert_eq!(at("amp_z_peak_m"), "2e-6");
        assert_eq!(at("mu"), "");
    }

    #[test]
    fn columns_are_distinct() {
        let mut c = COLUMNS.to_vec();
        c.sort_unstable();
        c.dedup();
        assert_eq!(c.len(), COLUMNS.len());
    }
}
