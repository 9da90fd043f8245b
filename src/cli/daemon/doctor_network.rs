//! `doctor`'s `output …` checks: every network output and input of the config
//! resolves, the unit's network drop-in lets it through, a TUIO target has a route,
//! a listening address can be bound (or is the running daemon's) and has a token
//! where it is reachable from other machines.

use super::doctor_check::Check;
use super::unit::{self, InstalledUnit};
use crowdtouch::config::{self, Config, OutputConfig};

/// The `output …` checks: every network output and input of the config.
pub fn check_network(
    cfg: &Config,
    installed: Option<&InstalledUnit>,
    daemon_running: bool,
) -> Vec<Check> {
    let policy = installed.map(InstalledUnit::network);
    unit::network_uses(cfg)
        .into_iter()
        .map(|u| {
            let name = format!("output {}", u.field);
            if let Some(why) = &u.unresolved {
                return Check::fail(
                    &name,
                    format!("{}: does not resolve: {why}", u.what),
                    "use an IP address, or a name /etc/hosts or DNS knows",
                );
            }
            if let Some(why) = policy.as_ref().and_then(|p| unit::blocked(p, &u)) {
                return Check::fail(
                    &name,
                    format!("{}: {why}", u.what),
                    "sudo systemctl daemon-reload && sudo systemctl restart crowdtouch (the \
                     generator remakes the unit's network drop-in from the config)",
                );
            }
            if u.listens {
                check_listener(cfg, &u, &name, daemon_running)
            } else {
                check_target(&u, &name)
            }
        })
        .collect()
}

/// A TUIO target: routable from here (a UDP `connect` asks the kernel for a route;
/// nothing is sent).
fn check_target(u: &unit::NetUse, name: &str) -> Check {
    for a in &u.addrs {
        let local: std::net::SocketAddr = if a.is_ipv4() {
            ([0, 0, 0, 0], 0).into()
        } else {
            (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
        };
        let routed = std::net::UdpSocket::bind(local).and_then(|s| s.connect(a));
        if let Err(e) = routed {
            return Check::fail(
                name,
                format!("{}: {a} is unreachable from this machine: {e}", u.what),
                "check the renderer's address and this machine's network (ip route get ADDRESS)",
            );
        }
    }
    Check::ok(
        name,
        format!(
            "{}: resolves to {} and has a route",
            u.what,
            u.addrs
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    )
}

/// A WebSocket or TUIO input address: bindable now, or in use by the running
/// daemon; a token where the address is not loopback.
fn check_listener(cfg: &Config, u: &unit::NetUse, name: &str, daemon_running: bool) -> Check {
    let needs_token = u.addrs.iter().any(|a| !config::is_loopback(a.ip()));
    let websocket = cfg.outputs.iter().find_map(|o| match o {
        OutputConfig::WebSocket { listen, token, .. }
            if u.field.starts_with("outputs") && u.what.contains(listen.as_str()) =>
        {
            Some(token.is_some())
        }
        _ => None,
    });
    if websocket == Some(false) && needs_token {
        return Check::fail(
            name,
            format!("{}: reachable from other machines without a token", u.what),
            "give the output a token (16+ characters), or listen on 127.0.0.1",
        );
    }
    let Some(addr) = u.addrs.first() else {
        return Check::ok(name, u.what.clone());
    };
    let bound = if websocket.is_some() {
        std::net::TcpListener::bind(addr).map(drop)
    } else {
        std::net::UdpSocket::bind(addr).map(drop)
    };
    match bound {
        Ok(()) => Check::ok(name, format!("{}: the address can be bound", u.what)),
        Err(e) if e.kind() == std::io::ErrorKind::AddrInUse && daemon_running => {
            Check::ok(name, format!("{}: in use, by the running daemon", u.what))
        }
        Err(e) => Check::fail(
            name,
            format!("{}: cannot be bound: {e}", u.what),
            "another program holds the port, or the address is not this machine's: \
             ss -ltnup shows who listens",
        ),
    }
}
