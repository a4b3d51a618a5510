//! The OPC UA server of `[opcua]` (async-opcua): its endpoints and security,
//! the address space of one rig ([`crate::space`]), and [`Output`], through
//! which the shell sets the state variables and emits the events.

use std::path::PathBuf;
use std::sync::Arc;

use opcua::crypto::SecurityPolicy;
use opcua::server::diagnostics::NamespaceMetadata;
use opcua::server::node_manager::memory::{simple_node_manager, SimpleNodeManager};
use opcua::server::{
    Server, ServerBuilder, ServerEndpoint, ServerHandle, ServerUserToken, ANONYMOUS_USER_TOKEN_ID,
};
use opcua::types::{DataValue, DateTime, MessageSecurityMode, NodeId, Variant};

use config::opcua::OpcuaConfig;
use frames::LeakEventFrame;

use crate::event::{LeakwatchEvent, NAMESPACE};
use crate::space::{self, RigNodes};
use crate::state::Value;

/// The name of leakwatch's node manager.
const MANAGER: &str = "leakwatch";
/// The id of the one user token (`[opcua] user`).
const USER_TOKEN: &str = "leakwatch-user";

/// The server's side the shell works with: the rig's nodes and the means to
/// change them.
pub struct Output {
    handle: ServerHandle,
    manager: Arc<SimpleNodeManager>,
    nodes: RigNodes,
    /// The certificate store made for this process (no `pki_dir`), removed at the end.
    scratch_pki: Option<PathBuf>,
}

/// The endpoint of `policy` (a name of [`config::opcua::POLICIES`]) for the user tokens
/// `tokens`; with a user on `None`, the password is encrypted with the server's
/// certificate (Basic256Sha256), never sent in the clear.
fn endpoint(policy: &str, tokens: &[String], user: bool) -> Result<ServerEndpoint, String> {
    let secure = |p| ServerEndpoint::new("/", p, MessageSecurityMode::SignAndEncrypt, tokens);
    Ok(match policy {
        "None" => {
            let mut e = ServerEndpoint::new_none("/", tokens);
            if user {
                e.password_security_policy = Some(SecurityPolicy::Basic256Sha256.to_string());
            }
            e
        }
        "Basic256Sha256" => secure(SecurityPolicy::Basic256Sha256),
        "Aes128Sha256RsaOaep" => secure(SecurityPolicy::Aes128Sha256RsaOaep),
        other => return Err(format!("[opcua] security_policies: {other:?} is not supported")),
    })
}

/// The server of `cfg` listening on `port` (the configured one, or another
/// from the command line) for rig `rig`, not yet running, and its [`Output`].
pub fn build(cfg: &OpcuaConfig, port: u16, rig: &str) -> Result<(Server, Output), String> {
    let user = cfg.credentials()?;
    let (pki, scratch_pki) = match &cfg.pki_dir {
        Some(d) => (d.clone(), None),
        None => {
            let d = std::env::temp_dir().join(format!("leakwatch-opcua-{}", std::process::id()));
            (d.clone(), Some(d))
        }
    };
    let tokens = vec![if user.is_some() {
        USER_TOKEN
    } else {
        ANONYMOUS_USER_TOKEN_ID
    }
    .to_string()];
    let mut b = ServerBuilder::new()
        .application_name(format!("leakwatch {rig}"))
        .application_uri(format!("urn:leakwatch:{rig}"))
        .product_uri("urn:leakwatch")
        .host(cfg.bind.clone())
        .port(port)
        .discovery_urls(vec!["/".to_string()])
        .pki_dir(pki)
        // a server certificate only where one is needed: a signing policy, or a password to encrypt
        .create_sample_keypair(cfg.pki_dir.is_some())
        .trust_client_certs(cfg.trust_client_certs)
        .diagnostics_enabled(false)
        // events and changes reach a subscription within 10 ms of their notification
        .subscription_poll_interval_ms(10)
        .with_node_manager(simple_node_manager(
            NamespaceMetadata {
                namespace_uri: NAMESPACE.to_string(),
                ..Default::default()
            },
            MANAGER,
        ));
    b.limits_mut().subscriptions.min_publishing_interval_ms = 10.0;
    b.limits_mut().subscriptions.min_sampling_interval_ms = 10.0;
    if let Some((name, pass)) = &user {
        b = b.add_user_token(
            USER_TOKEN,
            ServerUserToken::user_pass(name.as_str(), pass.as_str()),
        );
    }
    for (i, p) in cfg.security_policies.iter().enumerate() {
        b = b.add_endpoint(format!("endpoint-{i}"), endpoint(p, &tokens, user.is_some())?);
    }
    let (server, handle) = b
        .build()
        .map_err(|e| format!("the OPC UA server cannot be set up: {e}"))?;
    let manager = handle
        .node_managers()
        .get_by_name::<SimpleNodeManager>(MANAGER)
        .ok_or("the OPC UA server has no leakwatch node manager")?;
    let ns = handle
        .get_namespace_index(NAMESPACE)
        .ok_or("the OPC UA server has no leakwatch namespace")?;
    let nodes = {
        let mut space = manager.address_space().write();
        let nodes = space::build(&mut space, ns, rig);
        // the event type into the server's type tree, for the clients' event filters
        space.load_into_type_tree(&mut handle.type_tree().write());
        nodes
    };
    let output = Output {
        handle,
        manager,
        nodes,
        scratch_pki,
    };
    Ok((server, output))
}

fn variant(v: &Value) -> Variant {
    match v {
        Value::Bool(b) => Variant::from(*b),
        Value::Double(x) if x.is_nan() => Variant::Empty,
        Value::Double(x) => Variant::from(*x),
        Value::Str(s) => Variant::from(s.as_str()),
        Value::U32(n) => Variant::from(*n),
        Value::U64(n) => Variant::from(*n),
    }
}

impl Output {
    /// The rig's nodes.
    pub fn nodes(&self) -> &RigNodes {
        &self.nodes
    }

    /// Sets the state variables to `values` ([`crate::state::VARIABLES`] order), those
    /// that changed since `before` (all when `None`); subscribers are notified.
    pub fn set(&self, values: &[Value], before: Option<&[Value]>) -> Result<(), String> {
        let now = DateTime::now();
        let changed: Vec<(&NodeId, DataValue)> = self
            .nodes
            .variables
            .iter()
            .zip(values)
            .enumerate()
            .filter(|(i, (_, v))| before.is_none_or(|b| b.get(*i) != Some(*v)))
            .map(|(_, (id, v))| (id, DataValue::new_at(variant(v), now)))
            .collect();
        if changed.is_empty() {
            return Ok(());
        }
        self.manager
            .set_values(
                self.handle.subscriptions(),
                changed.into_iter().map(|(id, dv)| (id, None, dv)),
            )
            .map_err(|e| format!("cannot set the state variables: {e}"))
    }

    /// Emits `e` as an OPC UA event from the rig's object (the server passes it to
    /// the Server object's subscribers too); `time_ns`: the acquisition time of its
    /// sample, Unix ns.
    pub fn emit(&self, e: &LeakEventFrame, time_ns: u64) {
        let n = &self.nodes;
        let ev = LeakwatchEvent::of_frame(n.ns, &n.object, &n.rig, e, time_ns);
        self.handle
            .subscriptions()
            .notify_events(std::iter::once((&ev as &dyn opcua::nodes::Event, &n.object)));
    }

    /// Stops the server (its task then ends).
    pub fn stop(&self) {
        self.handle.cancel();
    }
}

impl Drop for Output {
    fn drop(&mut self) {
        if let Some(d) = &self.scratch_pki {
            let _ = std::fs::remove_dir_all(d);
        }
    }
}
