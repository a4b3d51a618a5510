//! `leakwatch stage opcua`: subscribes to a rig's estimates, health and
//! events, drains them every `--batch-ms`, emits each event as an OPC UA
//! event at once and sets the rig's state variables `[opcua] update_hz`
//! times a second, until SIGINT/SIGTERM.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig, Subscriber, WaitMode};
use clap::Parser;
use frames::{EstimateFrame, HealthFrame, LeakEventFrame};

use crate::server::{self, Output};
use crate::state::{RigState, Value};

/// Serve a rig's state and its leak and sensor events over OPC UA (read-only).
#[derive(Debug, Parser)]
#[command(name = "opcua", version)]
struct Args {
    /// Rig id.
    #[arg(long)]
    rig: String,
    /// Configuration file: its [opcua] section (bind, port, security, users).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Address to listen on (default [opcua] bind, 127.0.0.1).
    #[arg(long)]
    bind: Option<String>,
    /// TCP port (default [opcua] port, 4840).
    #[arg(long)]
    port: Option<u16>,
    /// State variables updated at most this often, Hz (default [opcua] update_hz).
    #[arg(long)]
    update_hz: Option<f64>,
    /// Time between two drains of the subscriptions, ms (1 to 100).
    #[arg(long, default_value_t = 10)]
    batch_ms: u64,
}

/// The subscriptions of the OPC UA output.
struct Feed {
    estimates: Subscriber<EstimateFrame>,
    health: Subscriber<HealthFrame>,
    events: Subscriber<LeakEventFrame>,
    /// Messages received: estimates, health, events.
    received: [u64; 3],
}

impl Feed {
    fn open(bus: &Bus) -> Result<Feed, String> {
        let e = |e: bus::BusError| e.to_string();
        Ok(Feed {
            estimates: bus.subscriber(WaitMode::Event).map_err(e)?,
            health: bus.subscriber(WaitMode::Event).map_err(e)?,
            events: bus.subscriber(WaitMode::Event).map_err(e)?,
            received: [0; 3],
        })
    }

    /// Takes everything buffered into `state`; each event is emitted by `out`
    /// as it is taken. Returns the number of events.
    fn drain(&mut self, state: &mut RigState, out: &Output) -> Result<u64, String> {
        let now = Instant::now();
        let s = |e: bus::BusError| e.to_string();
        let mut last = None;
        while let Some(r) = self.estimates.try_receive().map_err(s)? {
            self.received[0] += 1;
            last = Some(r.frame);
        }
        if let Some(e) = last {
            state.on_estimate(&e, now);
        }
        while let Some(r) = self.health.try_receive().map_err(s)? {
            self.received[1] += 1;
            state.on_health(&r.frame, now);
        }
        let mut n = 0;
        while let Some(r) = self.events.try_receive().map_err(s)? {
            self.received[2] += 1;
            n += 1;
            out.emit(&r.frame, bus::epoch_ns(r.frame.acq_mono_ns));
            state.on_event(&r.frame);
        }
        Ok(n)
    }
}

fn settings(args: &Args) -> Result<config::opcua::OpcuaConfig, String> {
    let mut cfg = config::Config::load_or_default(args.config.as_deref())?.opcua;
    if let Some(b) = &args.bind {
        cfg.bind = b.clone();
    }
    cfg.port = args.port.unwrap_or(cfg.port);
    cfg.update_hz = args.update_hz.unwrap_or(cfg.update_hz);
    cfg.validate()
        .map_err(|e| format!("{e} (command line or config)"))?;
    if !(1..=100).contains(&args.batch_ms) {
        return Err(format!("--batch-ms {}: must be 1 to 100 ms", args.batch_ms));
    }
    Ok(cfg)
}

fn announce(cfg: &config::opcua::OpcuaConfig, rig: &str) {
    if let Some(w) = cfg.exposure_warning() {
        bus::say!("opcua: warning: {w}");
    }
    bus::say!(
        "opcua: rig {rig}, OPC UA server on opc.tcp://{}:{}/ (security policies {}; {}; read-only), \
         Objects/{}/{rig} updated at {} Hz, events of LeakwatchEventType from it and the Server object",
        cfg.bind,
        cfg.port,
        cfg.security_policies.join(", "),
        match &cfg.user {
            Some(u) => format!("user {u} only, anonymous refused"),
            None => "anonymous".to_string(),
        },
        crate::space::FOLDER,
        cfg.update_hz,
    );
}

fn run(args: Args) -> Result<(), String> {
    let cfg = settings(&args)?;
    let bus_cfg = BusConfig::from_env().map_err(|e| e.to_string())?;
    // the run's one time base (LEAKWATCH_EPOCH_OFFSET_NS): event times are the log's
    bus::init_epoch_offset().map_err(|e| e.to_string())?;
    let bus = Bus::open(&args.rig, bus_cfg).map_err(|e| e.to_string())?;
    let mut feed = Feed::open(&bus)?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the OPC UA server's runtime: {e}"))?;
    let rig = bus.rig().as_str().to_string();
    let (server, out) = {
        let _in_runtime = rt.enter();
        server::build(&cfg, cfg.port, &rig)?
    };
    let task = rt.spawn(server.run());
    announce(&cfg, &rig);
    let r = serve(&cfg, &args, &mut feed, &out, &task);
    out.stop();
    let ended = rt.block_on(async { tokio::time::timeout(Duration::from_secs(3), task).await });
    if let Ok(Ok(Err(e))) = ended {
        r?;
        return Err(format!("the OPC UA server ended: {e}"));
    }
    r
}

/// The loop: drain every batch, set the variables when due, until a signal
/// or the server's end.
fn serve(
    cfg: &config::opcua::OpcuaConfig,
    args: &Args,
    feed: &mut Feed,
    out: &Output,
    task: &tokio::task::JoinHandle<Result<(), String>>,
) -> Result<(), String> {
    let stop = bus::stop_on_signals();
    let batch = Duration::from_millis(args.batch_ms);
    let period = Duration::from_secs_f64(1.0 / cfg.update_hz);
    let mut state = RigState::new();
    let mut shown: Option<Vec<Value>> = None;
    let mut next = Instant::now();
    let (start, cpu0) = (Instant::now(), live::cpu_time_s());
    let mut updates = 0u64;
    while !stop.load(Ordering::Relaxed) {
        if task.is_finished() {
            return Err(format!(
                "the OPC UA server stopped (is port {} on {} free?)",
                cfg.port, cfg.bind
            ));
        }
        std::thread::sleep(batch);
        let events = feed.drain(&mut state, out)?;
        let now = Instant::now();
        if now >= next || events > 0 {
            let values = state.values(now);
            out.set(&values, shown.as_deref())?;
            shown = Some(values);
            updates += 1;
            next = (next + period).max(now);
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let cpu = live::cpu_time_s() - cpu0;
    bus::say!(
        "opcua: stopped by signal after {wall:.1} s; received estimates {}, health {}, events {}; \
         {updates} updates of the state ({:.1} per s); CPU {cpu:.2} s ({:.1} % of one core)",
        feed.received[0],
        feed.received[1],
        feed.received[2],
        updates as f64 / wall.max(1e-9),
        100.0 * cpu / wall.max(1e-9)
    );
    Ok(())
}

/// Runs the OPC UA server process with command-line arguments `args` (the
/// first is the program name); the exit code says whether it succeeded.
pub fn opcua_main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    match run(Args::parse_from(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            bus::say!("opcua: error: {e}");
            ExitCode::FAILURE
        }
    }
}
