//! The process shells: `leakwatch stage liveview` (the Foxglove live view) and
//! `leakwatch stage gateway` (the Zenoh fleet gateway). Each subscribes to a
//! rig's topics ([`crate::Tap`]), drains them every `--batch-ms`, and runs
//! until SIGINT/SIGTERM; at the end it prints what it received and sent and
//! the CPU time it used.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig};
use clap::Parser;

use crate::{LiveTopic, Sink, Tap};

/// Serve a rig's frames, estimates, events and health to Foxglove over its
/// WebSocket protocol v1 (subprotocol foxglove.sdk.v1.1, foxglove.sdk.v1 or
/// foxglove.websocket.v1, answered with the one the client offers), each
/// message at its acquisition time as Unix time, the log's time.
#[derive(Debug, Parser)]
#[command(name = "liveview", version)]
struct ViewArgs {
    /// Rig id.
    #[arg(long)]
    rig: String,
    /// Configuration file: its [live_view] section (bind, port, rates, backlog).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Address to listen on (default [live_view] bind, 127.0.0.1).
    #[arg(long)]
    bind: Option<String>,
    /// TCP port (default [live_view] port, 8765; 0: any free port, printed).
    #[arg(long)]
    port: Option<u16>,
    /// Sensor frames sent at most this often, Hz (default [live_view] frames_hz).
    #[arg(long)]
    frames_hz: Option<f64>,
    /// Estimates sent at most this often, Hz (default [live_view] estimates_hz).
    #[arg(long)]
    estimates_hz: Option<f64>,
    /// Time between two drains of the subscriptions, ms (1 to 100).
    #[arg(long, default_value_t = 20)]
    batch_ms: u64,
}

/// Publish a rig's events, health and decimated estimates on Zenoh under
/// leakwatch/<rig>/<topic>.
#[derive(Debug, Parser)]
#[command(name = "gateway", version)]
struct GatewayArgs {
    /// Rig id.
    #[arg(long)]
    rig: String,
    /// Configuration file: its [zenoh] section (endpoints, scouting, rate).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Zenoh endpoint to listen on, e.g. tcp/0.0.0.0:7447 (repeatable; replaces [zenoh] listen).
    #[arg(long)]
    listen: Vec<String>,
    /// Zenoh endpoint to connect to, e.g. tcp/10.0.0.5:7447 (repeatable; replaces [zenoh] connect).
    #[arg(long)]
    connect: Vec<String>,
    /// Estimates published at most this often, Hz (default [zenoh] estimates_hz).
    #[arg(long)]
    estimates_hz: Option<f64>,
    /// Time between two drains of the subscriptions, ms (1 to 100).
    #[arg(long, default_value_t = 20)]
    batch_ms: u64,
}

fn open_bus(rig: &str) -> Result<Bus, String> {
    let cfg = BusConfig::from_env().map_err(|e| e.to_string())?;
    // the run's one time base (LEAKWATCH_EPOCH_OFFSET_NS): the messages' times are the log's
    bus::init_epoch_offset().map_err(|e| e.to_string())?;
    Bus::open(rig, cfg).map_err(|e| e.to_string())
}

fn check_batch(ms: u64) -> Result<Duration, String> {
    if (1..=100).contains(&ms) {
        Ok(Duration::from_millis(ms))
    } else {
        Err(format!("--batch-ms {ms}: must be 1 to 100 ms"))
    }
}

/// Drains `tap` into `sink` every `batch` until a signal; prints the counts and CPU time.
fn serve(stage: &str, tap: &mut Tap, sink: &mut impl Sink, batch: Duration) -> Result<(), String> {
    let stop = bus::stop_on_signals();
    let start = Instant::now();
    let cpu0 = crate::cpu_time_s();
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(batch);
        tap.drain(sink)?;
    }
    let wall = start.elapsed().as_secs_f64();
    let cpu = crate::cpu_time_s() - cpu0;
    let c = &tap.counts;
    let per = |v: &[u64; 4]| {
        LiveTopic::ALL
            .iter()
            .map(|t| format!("{} {}", t.name(), v[t.index()]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    bus::say!(
        "{stage}: stopped by signal after {wall:.1} s; received {}; sent {}; missing {}; \
         CPU {cpu:.2} s ({:.1} % of one core)",
        per(&c.received),
        per(&c.sent),
        per(&c.missing),
        100.0 * cpu / wall.max(1e-9)
    );
    Ok(())
}

fn liveview(args: ViewArgs) -> Result<(), String> {
    let mut cfg = config::Config::load_or_default(args.config.as_deref())?.live_view;
    if let Some(b) = args.bind {
        cfg.bind = b;
    }
    cfg.frames_hz = args.frames_hz.unwrap_or(cfg.frames_hz);
    cfg.estimates_hz = args.estimates_hz.unwrap_or(cfg.estimates_hz);
    // port 0 (any free port) only from the command line
    let port = args.port.unwrap_or(cfg.port);
    cfg.port = port.max(1);
    cfg.validate()
        .map_err(|e| format!("{e} (command line or config)"))?;
    let batch = check_batch(args.batch_ms)?;
    let bus = open_bus(&args.rig)?;
    let mut tap = Tap::open(&bus, cfg.frames_hz, cfg.estimates_hz)?;
    let token = cfg.resolve_token()?;
    if let Some(w) = cfg.exposure_warning() {
        bus::say!("liveview: warning: {w}");
    }
    let mut view = crate::view::LiveView::start(bus.rig().as_str(), &cfg.bind, port, cfg.backlog, token)?;
    bus::say!(
        "liveview: rig {}, Foxglove WebSocket on ws://{}:{} (subprotocols {}; frames at {} Hz, estimates at {} Hz, \
         events and health: every one; backlog {} messages per client)",
        bus.rig(),
        cfg.bind,
        view.port(),
        crate::view::SUBPROTOCOLS.join(", "),
        cfg.frames_hz,
        cfg.estimates_hz,
        cfg.backlog
    );
    let r = serve("liveview", &mut tap, &mut view, batch);
    view.stop();
    r
}

fn gateway(args: GatewayArgs) -> Result<(), String> {
    let mut cfg = config::Config::load_or_default(args.config.as_deref())?.zenoh;
    if !args.listen.is_empty() {
        cfg.listen = args.listen;
    }
    if !args.connect.is_empty() {
        cfg.connect = args.connect;
    }
    cfg.estimates_hz = args.estimates_hz.unwrap_or(cfg.estimates_hz);
    cfg.validate()
        .map_err(|e| format!("{e} (command line or config)"))?;
    let batch = check_batch(args.batch_ms)?;
    let bus = open_bus(&args.rig)?;
    let mut tap = Tap::open(&bus, 1.0, cfg.estimates_hz)?;
    let mut gw = crate::gateway::Gateway::open(bus.rig().as_str(), &cfg)?;
    bus::say!(
        "gateway: rig {rig}, publishing leakwatch/{rig}/events, health and estimates (at {} Hz, {}) on zenoh \
         (peer; listening on [{}]; connecting to [{}]; multicast scouting {})",
        cfg.estimates_hz,
        match &cfg.key_file {
            Some(f) => format!("signed with the key of {}", f.display()),
            None => "unsigned: no [zenoh] key_file".to_string(),
        },
        cfg.listen.join(", "),
        cfg.connect.join(", "),
        if cfg.multicast_scouting { "on" } else { "off" },
        rig = bus.rig(),
    );
    serve("gateway", &mut tap, &mut gw, batch)?;
    if gw.errors > 0 {
        bus::say!("gateway: {} messages could not be sent", gw.errors);
    }
    Ok(())
}

fn exit(stage: &str, r: Result<(), String>) -> ExitCode {
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            bus::say!("{stage}: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Runs the live view process with command-line arguments `args` (the first is
/// the program name); the exit code says whether it succeeded.
pub fn liveview_main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    exit("liveview", liveview(ViewArgs::parse_from(args)))
}

/// Runs the Zenoh gateway process with command-line arguments `args` (the
/// first is the program name); the exit code says whether it succeeded.
pub fn gateway_main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    exit("gateway", gateway(GatewayArgs::parse_from(args)))
}
