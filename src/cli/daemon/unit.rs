//! The service's network, from the config: the systemd unit ships with no network
//! at all (`PrivateNetwork=yes`, `RestrictAddressFamilies=AF_UNIX AF_NETLINK`), and
//! a generator (`crowdtouch unit-network --generator DIR`, run by systemd at boot
//! and on every `systemctl daemon-reload`) writes a drop-in that opens exactly what
//! the config's outputs and inputs name: the IP families, and `IPAddressAllow=`
//! for their addresses behind `IPAddressDeny=any` (systemd.resource-control(5)).
//!
//! The same reading of the installed unit and its drop-ins tells `check-config` and
//! `doctor` whether the service, as systemd would start it now, can reach what the
//! config names (a drop-in made before the config changed is out of date until the
//! next daemon-reload).

use crowdtouch::config::{Config, InputConfig, OutputConfig};
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, ToSocketAddrs};
use std::path::{Path, PathBuf};

/// The unit's name.
pub const UNIT: &str = "crowdtouch.service";
/// The user the unit runs the daemon as (`User=`), created by its sysusers file.
pub const SERVICE_USER: &str = "crowdtouch";
/// The config the unit's `ExecStart` names.
pub const SERVICE_CONFIG: &str = "/etc/crowdtouch/crowdtouch.ron";
/// The unit's `RuntimeDirectory=`, created by systemd when it starts the service.
pub const SERVICE_RUNTIME_DIR: &str = "/run/crowdtouch";
/// The generated drop-in's file name.
pub const DROPIN_NAME: &str = "50-crowdtouch-network.conf";

/// Where systemd looks for system units, first wins (systemd.unit(5)), relative to
/// the root.
const UNIT_DIRS: [&str; 7] = [
    "etc/systemd/system",
    "run/systemd/system",
    "run/systemd/generator",
    "usr/local/lib/systemd/system",
    "usr/lib/systemd/system",
    "lib/systemd/system",
    "run/systemd/generator.late",
];

/// An installed unit: its file and drop-ins, and its `[Service]` settings in the
/// order systemd applies them.
#[derive(Debug, Default)]
pub struct InstalledUnit {
    /// The unit file.
    pub path: PathBuf,
    /// Its drop-ins, in the order applied.
    pub dropins: Vec<PathBuf>,
    /// `(key, value)` of every `[Service]` line, unit first, then the drop-ins.
    settings: Vec<(String, String)>,
}

/// The unit under `root`, if installed.
pub fn installed(root: &Path) -> Option<InstalledUnit> {
    let path = UNIT_DIRS
        .iter()
        .map(|d| root.join(d).join(UNIT))
        .find(|p| p.is_file())?;
    // Drop-ins: by file name across every directory; a name in an earlier
    // directory hides the same name in a later one.
    let mut dropins: Vec<(String, PathBuf)> = Vec::new();
    for d in UNIT_DIRS {
        let Ok(rd) = std::fs::read_dir(root.join(d).join(format!("{UNIT}.d"))) else {
            continue;
        };
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".conf") && !dropins.iter().any(|(n, _)| *n == name) {
                dropins.push((name, e.path()));
            }
        }
    }
    dropins.sort();
    let mut unit = InstalledUnit {
        path,
        dropins: dropins.into_iter().map(|(_, p)| p).collect(),
        settings: Vec::new(),
    };
    for f in std::iter::once(unit.path.clone()).chain(unit.dropins.clone()) {
        if let Ok(text) = std::fs::read_to_string(&f) {
            unit.settings.extend(service_settings(&text));
        }
    }
    Some(unit)
}

/// The `key=value` lines of a unit file's `[Service]` section.
fn service_settings(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut in_service = false;
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            in_service = line == "[Service]";
        } else if in_service && !line.starts_with(['#', ';']) {
            if let Some((k, v)) = line.split_once('=') {
                out.push((k.trim().to_string(), v.trim().to_string()));
            }
        }
    }
    out
}

impl InstalledUnit {
    /// The last value of a single-valued setting.
    pub fn last(&self, key: &str) -> Option<&str> {
        self.settings
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// A list setting's items: each line adds its words, an empty one clears.
    fn list(&self, key: &str) -> Option<Vec<String>> {
        let mut out: Option<Vec<String>> = None;
        for (_, v) in self.settings.iter().filter(|(k, _)| k == key) {
            if v.is_empty() {
                out = None;
            } else {
                out.get_or_insert_with(Vec::new)
                    .extend(v.split_whitespace().map(str::to_string));
            }
        }
        out
    }

    /// What the unit lets the daemon do on the network.
    pub fn network(&self) -> NetPolicy {
        let families = match self.list("RestrictAddressFamilies") {
            None => Families::Any,
            Some(v) if v.first().is_some_and(|f| f.starts_with('~')) => Families::Except(
                v.iter()
                    .map(|f| f.trim_start_matches('~').to_string())
                    .collect(),
            ),
            Some(v) => Families::Only(v),
        };
        let ranges = |key| {
            self.list(key)
                .unwrap_or_default()
                .iter()
                .flat_map(|w| parse_ranges(w))
                .collect()
        };
        NetPolicy {
            private_network: self
                .last("PrivateNetwork")
                .is_some_and(|v| matches!(v, "yes" | "true" | "1" | "on")),
            families,
            allow: ranges("IPAddressAllow"),
            deny: ranges("IPAddressDeny"),
        }
    }
}

/// `RestrictAddressFamilies=`.
#[derive(Clone, Debug, PartialEq)]
pub enum Families {
    /// Not restricted.
    Any,
    /// Only these.
    Only(Vec<String>),
    /// All but these (`~`).
    Except(Vec<String>),
}

impl Families {
    fn allows(&self, family: &str) -> bool {
        match self {
            Families::Any => true,
            Families::Only(v) => v.iter().any(|f| f == family),
            Families::Except(v) => !v.iter().any(|f| f == family),
        }
    }
}

/// An address prefix of `IPAddressAllow=`/`IPAddressDeny=`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IpRange {
    addr: IpAddr,
    prefix: u8,
}

impl IpRange {
    fn contains(&self, ip: IpAddr) -> bool {
        match (self.addr, ip) {
            (IpAddr::V4(a), IpAddr::V4(b)) => {
                let mask = u32::MAX
                    .checked_shl(32 - u32::from(self.prefix))
                    .unwrap_or(0);
                u32::from(a) & mask == u32::from(b) & mask
            }
            (IpAddr::V6(a), IpAddr::V6(b)) => {
                let mask = u128::MAX
                    .checked_shl(128 - u32::from(self.prefix))
                    .unwrap_or(0);
                u128::from(a) & mask == u128::from(b) & mask
            }
            _ => false,
        }
    }
}

/// The prefixes one word of `IPAddressAllow=` names (its symbolic names too);
/// nothing for a word systemd would reject.
fn parse_ranges(word: &str) -> Vec<IpRange> {
    let r = |addr: IpAddr, prefix: u8| IpRange { addr, prefix };
    match word {
        "any" => vec![
            r(Ipv4Addr::UNSPECIFIED.into(), 0),
            r(Ipv6Addr::UNSPECIFIED.into(), 0),
        ],
        "localhost" => vec![
            r(Ipv4Addr::new(127, 0, 0, 0).into(), 8),
            r(Ipv6Addr::LOCALHOST.into(), 128),
        ],
        "link-local" => vec![
            r(Ipv4Addr::new(169, 254, 0, 0).into(), 16),
            r(Ipv6Addr::new(0xfe80, 0, 0, 0, 0, 0, 0, 0).into(), 64),
        ],
        "multicast" => vec![
            r(Ipv4Addr::new(224, 0, 0, 0).into(), 4),
            r(Ipv6Addr::new(0xff00, 0, 0, 0, 0, 0, 0, 0).into(), 8),
        ],
        w => {
            let (a, p) = w.split_once('/').unwrap_or((w, ""));
            let Ok(addr) = a.parse::<IpAddr>() else {
                return vec![];
            };
            let max = if addr.is_ipv4() { 32 } else { 128 };
            let prefix = if p.is_empty() {
                Some(max)
            } else {
                p.parse::<u8>().ok().filter(|p| *p <= max)
            };
            prefix.map(|p| r(addr, p)).into_iter().collect()
        }
    }
}

/// What a unit lets the daemon do on the network.
#[derive(Clone, Debug, PartialEq)]
pub struct NetPolicy {
    /// `PrivateNetwork=yes`: a namespace of its own, only its own loopback.
    pub private_network: bool,
    /// `RestrictAddressFamilies=`.
    pub families: Families,
    /// `IPAddressAllow=`.
    pub allow: Vec<IpRange>,
    /// `IPAddressDeny=`.
    pub deny: Vec<IpRange>,
}

impl NetPolicy {
    /// Whether packets to or from `ip` pass: an allowed prefix wins, then a denied
    /// one refuses, else they pass (systemd.resource-control(5)).
    fn passes(&self, ip: IpAddr) -> bool {
        self.allow.iter().any(|r| r.contains(ip)) || !self.deny.iter().any(|r| r.contains(ip))
    }
}

/// One thing of the config that uses the network.
#[derive(Clone, Debug, PartialEq)]
pub struct NetUse {
    /// The config field (`outputs[0].target`).
    pub field: String,
    /// What it is, for people (`TUIO target 10.0.0.7:3333`).
    pub what: String,
    /// The addresses it talks to (a TUIO target's), or listens on.
    pub addrs: Vec<SocketAddr>,
    /// It listens (peers are whoever connects) rather than sends to `addrs`.
    pub listens: bool,
    /// The name did not resolve (why).
    pub unresolved: Option<String>,
}

/// Every output and input of `cfg` that uses the network, its addresses resolved.
pub fn network_uses(cfg: &Config) -> Vec<NetUse> {
    let mut out = Vec::new();
    let mut add = |field: String, what: String, addr: &str, listens: bool| {
        let (addrs, unresolved) = match addr.to_socket_addrs() {
            Ok(a) => (a.collect::<Vec<_>>(), None),
            Err(e) => (Vec::new(), Some(e.to_string())),
        };
        let unresolved = unresolved.or_else(|| {
            addrs
                .is_empty()
                .then(|| "resolves to no address".to_string())
        });
        out.push(NetUse {
            field,
            what,
            addrs,
            listens,
            unresolved,
        });
    };
    for (i, o) in cfg.outputs.iter().enumerate() {
        match o {
            OutputConfig::Tuio { target, .. } => add(
                format!("outputs[{i}].target"),
                format!("TUIO target {target}"),
                target,
                false,
            ),
            OutputConfig::WebSocket { listen, .. } => add(
                format!("outputs[{i}].listen"),
                format!("WebSocket/viewer on {listen}"),
                listen,
                true,
            ),
        }
    }
    for (i, input) in cfg.inputs.iter().enumerate() {
        if let InputConfig::Tuio { listen, .. } = input {
            add(
                format!("inputs[{i}].listen"),
                format!("TUIO input on {listen}"),
                listen,
                true,
            );
        }
    }
    out
}

/// Why the unit's `policy` would stop `u` from working, if it would.
pub fn blocked(policy: &NetPolicy, u: &NetUse) -> Option<String> {
    let families: Vec<&str> = u
        .addrs
        .iter()
        .map(|a| if a.is_ipv4() { "AF_INET" } else { "AF_INET6" })
        .collect();
    if let Some(f) = families.iter().find(|f| !policy.families.allows(f)) {
        return Some(format!(
            "the unit's RestrictAddressFamilies= does not allow {f}: the daemon cannot open its socket"
        ));
    }
    if policy.private_network {
        let all_loopback = u.addrs.iter().all(|a| a.ip().is_loopback());
        return Some(if u.listens && all_loopback {
            "the unit's PrivateNetwork=yes gives the daemon a loopback of its own: the \
             kiosk's own browser and clients cannot reach it"
                .to_string()
        } else {
            "the unit's PrivateNetwork=yes leaves the daemon no network but its own loopback"
                .to_string()
        });
    }
    // A listener's peers: loopback ones for a loopback address, any one otherwise
    // (checked against one address of each kind).
    let peers: Vec<IpAddr> = u
        .addrs
        .iter()
        .map(|a| match (u.listens, a.ip()) {
            (false, ip) => ip,
            (true, ip) if ip.is_loopback() => ip,
            (true, IpAddr::V4(_)) => Ipv4Addr::new(192, 0, 2, 1).into(),
            (true, IpAddr::V6(_)) => Ipv6Addr::new(0x2001, 0xdb8, 0, 0, 0, 0, 0, 1).into(),
        })
        .collect();
    if let Some(ip) = peers.iter().find(|ip| !policy.passes(**ip)) {
        let whom = if u.listens && !ip.is_loopback() {
            "clients from other hosts".to_string()
        } else {
            ip.to_string()
        };
        return Some(format!(
            "the unit's IPAddressDeny=/IPAddressAllow= drop packets of {whom}"
        ));
    }
    None
}

/// The drop-in that opens what `cfg` names and nothing else.
pub fn dropin(cfg: &Config, config_path: &Path) -> String {
    let uses = network_uses(cfg);
    let mut out = format!(
        "# Generated by `crowdtouch unit-network` from {} (systemctl daemon-reload\n\
         # makes it again). Do not edit: override in /etc/systemd/system/{UNIT}.d/.\n[Service]\n",
        config_path.display()
    );
    if uses.is_empty() {
        out.push_str(
            "# No network output or input in the config: no network at all.\n\
             PrivateNetwork=yes\nRestrictAddressFamilies=AF_UNIX AF_NETLINK\nIPAddressDeny=any\n",
        );
        return out;
    }
    let mut allow: Vec<String> = Vec::new();
    let mut push = |s: String| {
        if !allow.contains(&s) {
            allow.push(s);
        }
    };
    for u in &uses {
        let _ = std::fmt::Write::write_fmt(&mut out, format_args!("# {}: {}\n", u.field, u.what));
        if u.unresolved.is_some() {
            // A name that does not resolve now may later: its address is unknown.
            push("any".into());
            continue;
        }
        for a in &u.addrs {
            match (u.listens, a.ip()) {
                (true, ip) if ip.is_loopback() => push("localhost".into()),
                (true, _) => push("any".into()),
                (false, ip) if ip.is_loopback() => push("localhost".into()),
                (false, ip) => push(ip.to_string()),
            }
        }
    }
    if allow.iter().any(|a| a == "any") {
        allow = vec!["any".into()];
    }
    out.push_str(
        "PrivateNetwork=no\nRestrictAddressFamilies=\n\
         RestrictAddressFamilies=AF_UNIX AF_NETLINK AF_INET AF_INET6\nIPAddressDeny=any\n",
    );
    out.push_str(&format!("IPAddressAllow={}\n", allow.join(" ")));
    out
}

/// `crowdtouch unit-network`: prints the drop-in for `config` (the service's by
/// default); with `generator`, writes it where systemd reads a generator's output
/// (`DIR/crowdtouch.service.d/`) and never fails: a config that does not load gets
/// the drop-in of no network, and the reason in the drop-in and on stderr (the
/// journal, at boot).
pub fn unit_network(config: Option<&Path>, generator: Option<&Path>) -> anyhow::Result<i32> {
    use crate::cli::common::output::{errln, outln};
    let path = config.unwrap_or(Path::new(SERVICE_CONFIG));
    let text = match Config::load(path) {
        Ok(cfg) => dropin(&cfg, path),
        Err(e) if generator.is_some() => {
            let _ = errln!("crowdtouch-network-generator: {e}; the service gets no network");
            let mut t = dropin(&Config::embedded_default(), path);
            for l in format!("{e}").lines() {
                t.insert_str(0, &format!("# {l}\n"));
            }
            t.insert_str(0, "# The config did not load; no network until it does:\n");
            t
        }
        Err(e) => return Err(e.into()),
    };
    match generator {
        None => outln!("{}", text.trim_end())?,
        Some(dir) => {
            let d = dir.join(format!("{UNIT}.d"));
            std::fs::create_dir_all(&d)?;
            std::fs::write(d.join(DROPIN_NAME), text)?;
        }
    }
    Ok(0)
}

/// `check-config`'s warnings about the installed unit: each network output or
/// input the unit (with the drop-ins there are now) would block, at its field.
pub fn unit_findings(cfg: &Config, root: &Path) -> Vec<crowdtouch::pipeline::Finding> {
    let Some(unit) = installed(root) else {
        return Vec::new();
    };
    let policy = unit.network();
    network_uses(cfg)
        .iter()
        .filter_map(|u| {
            let why = blocked(&policy, u)?;
            Some(crowdtouch::pipeline::Finding {
                field: u.field.clone(),
                severity: crowdtouch::pipeline::Severity::Warning,
                message: format!(
                    "the installed {UNIT} would block the {}: {why}; `sudo systemctl \
                     daemon-reload && sudo systemctl restart crowdtouch` remakes its network \
                     drop-in from the config",
                    u.what
                ),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(outputs: &str, inputs: Option<&str>) -> Config {
        let mut c = Config::embedded_default();
        c.outputs = ron::from_str(outputs).unwrap();
        if let Some(i) = inputs {
            c.inputs = ron::from_str(i).unwrap();
        }
        c
    }

    fn unit(root: &Path, dir: &str, name: &str, text: &str) {
        let p = root.join(dir).join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    const SHIPPED: &str = include_str!("../../../systemd/crowdtouch.service");

    #[test]
    fn the_shipped_unit_alone_has_no_network() {
        let root = tempfile::tempdir().unwrap();
        unit(root.path(), "lib/systemd/system", UNIT, SHIPPED);
        let p = installed(root.path()).unwrap().network();
        assert!(p.private_network);
        assert!(!p.families.allows("AF_INET"));
        let c = cfg("[Tuio(target: \"127.0.0.1:3333\")]", None);
        let u = &network_uses(&c)[0];
        assert!(blocked(&p, u).unwrap().contains("AF_INET"));
    }

    #[test]
    fn the_generated_dropin_opens_what_the_config_names_and_nothing_else() {
        let c = cfg(
            "[Tuio(target: \"192.0.2.7:3333\"), WebSocket(listen: \"127.0.0.1:8080\")]",
            None,
        );
        let text = dropin(&c, Path::new(SERVICE_CONFIG));
        assert!(
            text.contains("IPAddressAllow=192.0.2.7 localhost\n"),
            "{text}"
        );
        let root = tempfile::tempdir().unwrap();
        unit(root.path(), "lib/systemd/system", UNIT, SHIPPED);
        unit(
            root.path(),
            &format!("run/systemd/generator/{UNIT}.d"),
            DROPIN_NAME,
            &text,
        );
        let with_dropin = installed(root.path()).unwrap();
        assert_eq!(with_dropin.dropins.len(), 1);
        let p = with_dropin.network();
        assert!(!p.private_network);
        for u in network_uses(&c) {
            assert_eq!(blocked(&p, &u), None, "{u:?}");
        }
        // A renderer the drop-in was not made for is blocked.
        let other = cfg("[Tuio(target: \"198.51.100.9:3333\")]", None);
        let why = blocked(&p, &network_uses(&other)[0]).unwrap();
        assert!(why.contains("IPAddressDeny"), "{why}");
        // So is a viewer for other hosts.
        let wide = cfg(
            "[WebSocket(listen: \"0.0.0.0:8080\", token: Some(\"0123456789abcdef\"))]",
            None,
        );
        assert!(blocked(&p, &network_uses(&wide)[0])
            .unwrap()
            .contains("other hosts"));
        // An override in /etc wins over the generated one of the same name.
        unit(
            root.path(),
            &format!("etc/systemd/system/{UNIT}.d"),
            DROPIN_NAME,
            "[Service]\nPrivateNetwork=yes\n",
        );
        let p = installed(root.path()).unwrap().network();
        assert!(p.private_network);
    }

    #[test]
    fn a_config_without_network_gets_none_and_a_wide_listener_any() {
        let none = dropin(&Config::embedded_default(), Path::new("c.ron"));
        assert!(none.contains("PrivateNetwork=yes") && !none.contains("AF_INET"));
        let wide = cfg(
            "[WebSocket(listen: \"0.0.0.0:8080\", token: Some(\"0123456789abcdef\"))]",
            Some("[Tuio(listen: \"127.0.0.1:3333\")]"),
        );
        let text = dropin(&wide, Path::new("c.ron"));
        assert!(text.contains("IPAddressAllow=any\n"), "{text}");
        assert_eq!(network_uses(&wide).len(), 2);
    }

    #[test]
    fn ranges_and_families_read_as_systemd_does() {
        let any = parse_ranges("any");
        assert!(any
            .iter()
            .any(|r| r.contains("203.0.113.5".parse().unwrap())));
        let net = parse_ranges("10.1.0.0/16");
        assert!(net[0].contains("10.1.200.3".parse().unwrap()));
        assert!(!net[0].contains("10.2.0.1".parse().unwrap()));
        assert!(parse_ranges("10.0.0.0/40").is_empty());
        assert!(parse_ranges("localhost")[1].contains(Ipv6Addr::LOCALHOST.into()));
        assert!(Families::Except(vec!["AF_INET".into()]).allows("AF_UNIX"));
        assert!(!Families::Except(vec!["AF_INET".into()]).allows("AF_INET"));
        let root = tempfile::tempdir().unwrap();
        unit(
            root.path(),
            "etc/systemd/system",
            UNIT,
            "[Unit]\nPrivateNetwork=yes\n[Service]\nIPAddressDeny=any\nIPAddressDeny=\nRestrictAddressFamilies=AF_UNIX\nRestrictAddressFamilies=AF_INET\n",
        );
        let p = installed(root.path()).unwrap().network();
        assert!(!p.private_network, "only [Service] counts");
        assert!(p.deny.is_empty(), "an empty assignment clears the list");
        assert_eq!(
            p.families,
            Families::Only(vec!["AF_UNIX".into(), "AF_INET".into()])
        );
    }
}
