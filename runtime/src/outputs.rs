//! The run's output stages (the live view, the Zenoh gateway, the OPC UA
//! server), each set, checked and said before anything starts.

use std::path::Path;

use bus::say as errln;
use config::Config;
use pipeline::out::outln;

use crate::args::RunArgs;
use crate::stages::Stage;

/// The stages of the run ([`crate::stages::run_stages`]): the live view
/// (`--live-view [PORT]` or `[live_view] enabled`) and the Zenoh gateway
/// (`--zenoh`, `--zenoh-connect` or `[zenoh] enabled`) and the OPC UA server
/// (`--opcua [PORT]` or `[opcua] enabled`) set in `cfg` for the stages to read,
/// checked (the live view's and the OPC UA server's ports free), and said on the console.
pub(crate) fn live_stages(
    args: &RunArgs,
    cfg: &mut Config,
    out_dir: &Path,
    inputs: &[&Path],
    quiet: bool,
    processes: &[Stage],
) -> Result<Vec<Stage>, String> {
    if let Some(port) = args.live_view {
        cfg.live_view.enabled = true;
        if port != 0 {
            cfg.live_view.port = port;
        }
    }
    if args.zenoh || !args.zenoh_connect.is_empty() {
        cfg.zenoh.enabled = true;
    }
    if !args.zenoh_connect.is_empty() {
        cfg.zenoh.connect = args.zenoh_connect.clone();
    }
    if let Some(port) = args.opcua {
        cfg.opcua.enabled = true;
        if port != 0 {
            cfg.opcua.port = port;
        }
    }
    cfg.live_view.validate()?;
    cfg.zenoh.validate()?;
    cfg.opcua.validate()?;
    opcua_stage(cfg, quiet)?;
    let v = &cfg.live_view;
    if v.enabled {
        // the live view binds it again at once
        std::net::TcpListener::bind((v.bind.as_str(), v.port)).map_err(|e| {
            format!(
                "--live-view {}: cannot listen on {}:{}: {e}",
                v.port, v.bind, v.port
            )
        })?;
    }
    if v.enabled {
        // the shipped Foxglove layout with this rig's topics, beside the run's outputs
        let layout = out_dir.join(live::layout::LAYOUT_FILE_NAME);
        pipeline::out::write(
            &layout,
            live::layout::for_rig(&args.rig).as_bytes(),
            args.force,
            inputs,
        )?;
        if let Some(w) = v.exposure_warning() {
            errln!("leakwatch run: warning: {w}");
        }
        if !quiet {
            outln!(
                "live view: ws://{}:{}{} (Foxglove: Open connection, Foxglove WebSocket; frames {} Hz, estimates {} Hz)",
                v.bind,
                v.port,
                if v.token.is_some() || v.token_file.is_some() {
                    "/?token=TOKEN (the [live_view] token)"
                } else {
                    ""
                },
                v.frames_hz,
                v.estimates_hz
            );
            outln!(
                "live view layout: {} (Foxglove: Layouts, Import from file; {} for rig {})",
                layout.display(),
                live::layout::LAYOUT_REPO_PATH,
                args.rig
            );
        }
    }
    if cfg.zenoh.enabled && !quiet {
        outln!(
            "zenoh: publishing leakwatch/{}/{{events,health,estimates}}, connecting to [{}]",
            args.rig,
            cfg.zenoh.connect.join(", ")
        );
    }
    let outputs = crate::stages::Outputs {
        live_view: v.enabled,
        zenoh: cfg.zenoh.enabled,
        opcua: cfg.opcua.enabled,
    };
    let stages = crate::stages::run_stages(processes, outputs);
    for name in stages.iter().filter(|n| crate::stages::is_output(**n)) {
        pipeline::out::check(&out_dir.join(format!("{name}.log")), args.force, inputs)?;
    }
    Ok(stages)
}

/// The OPC UA server of `[opcua]`, when enabled: its port checked free (the stage
/// binds it again at once) and its endpoint said on the console.
fn opcua_stage(cfg: &Config, quiet: bool) -> Result<(), String> {
    let o = &cfg.opcua;
    if !o.enabled {
        return Ok(());
    }
    std::net::TcpListener::bind((o.bind.as_str(), o.port))
        .map_err(|e| format!("--opcua {}: cannot listen on {}:{}: {e}", o.port, o.bind, o.port))?;
    if let Some(w) = o.exposure_warning() {
        errln!("leakwatch run: warning: {w}");
    }
    if !quiet {
        outln!(
            "opcua: opc.tcp://{}:{}/ (Objects/Leakwatch/<rig>, read-only; {}; security {}; docs/opcua.md)",
            o.bind,
            o.port,
            match &o.user {
                Some(u) => format!("user {u}"),
                None => "anonymous".to_string(),
            },
            o.security_policies.join(", ")
        );
    }
    Ok(())
}
