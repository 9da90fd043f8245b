//! Who is privileged on the Unix socket: the peer's credentials (`SO_PEERCRED`)
//! against the config's lists.
//!
//! A privileged client receives the raw touches and may send commands; any other
//! client is read-only (`session.rs`). Privileged are: root, the daemon's own user,
//! and any user or group (the peer's group or one of its supplementary groups) the
//! config lists in `socket.privileged`.

use std::os::fd::AsFd;

/// The users and groups (numeric ids, resolved from the config at start) whose
/// clients are privileged besides root and the daemon's own user.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PeerPolicy {
    /// User ids.
    pub users: Vec<u32>,
    /// Group ids.
    pub groups: Vec<u32>,
}

/// A peer's credentials: its user, its group and supplementary groups.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PeerCredentials {
    /// User id.
    pub uid: u32,
    /// Groups: the process's group first, then its supplementary groups when known.
    pub gids: Vec<u32>,
}

impl PeerPolicy {
    /// Whether a peer with `peer`'s credentials is privileged in a daemon running
    /// as `own_uid`.
    pub fn privileged(&self, peer: &PeerCredentials, own_uid: u32) -> bool {
        peer.uid == 0
            || peer.uid == own_uid
            || self.users.contains(&peer.uid)
            || peer.gids.iter().any(|g| self.groups.contains(g))
    }
}

/// The credentials of the process at the other end of `stream` (`SO_PEERCRED`,
/// and its supplementary groups from `/proc/<pid>/status` when readable). `None`
/// when the kernel does not say (the client is then read-only).
pub fn peer_credentials(stream: &impl AsFd) -> Option<PeerCredentials> {
    let cred =
        nix::sys::socket::getsockopt(stream, nix::sys::socket::sockopt::PeerCredentials).ok()?;
    let mut gids = vec![cred.gid()];
    if cred.pid() > 0 {
        if let Ok(status) = std::fs::read_to_string(format!("/proc/{}/status", cred.pid())) {
            gids.extend(supplementary_groups(&status));
        }
    }
    Some(PeerCredentials {
        uid: cred.uid(),
        gids,
    })
}

/// The `Groups:` line of a `/proc/<pid>/status` text.
fn supplementary_groups(status: &str) -> Vec<u32> {
    status
        .lines()
        .find_map(|l| l.strip_prefix("Groups:"))
        .map(|g| {
            g.split_whitespace()
                .filter_map(|n| n.parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peer(uid: u32, gids: &[u32]) -> PeerCredentials {
        PeerCredentials {
            uid,
            gids: gids.to_vec(),
        }
    }

    #[test]
    fn root_the_own_user_and_the_listed_are_privileged() {
        let none = PeerPolicy::default();
        assert!(none.privileged(&peer(0, &[0]), 1000), "root");
        assert!(
            none.privileged(&peer(1000, &[1000]), 1000),
            "the daemon's user"
        );
        assert!(!none.privileged(&peer(1001, &[1001]), 1000), "anyone else");
        let listed = PeerPolicy {
            users: vec![1001],
            groups: vec![44],
        };
        assert!(listed.privileged(&peer(1001, &[1001]), 1000));
        assert!(
            listed.privileged(&peer(1002, &[1002, 44]), 1000),
            "by a supplementary group"
        );
        assert!(!listed.privileged(&peer(1003, &[1003, 45]), 1000));
    }

    #[test]
    fn supplementary_groups_are_read_from_proc_status() {
        let status = "Name:\tx\nUid:\t1\t1\t1\t1\nGroups:\t4 24 27 \nVmPeak:\t1 kB\n";
        assert_eq!(supplementary_groups(status), vec![4, 24, 27]);
        assert_eq!(supplementary_groups("Name:\tx\n"), Vec::<u32>::new());
    }

    #[test]
    fn a_socket_pair_reports_our_own_credentials() {
        let (a, _b) = std::os::unix::net::UnixStream::pair().expect("pair");
        let c = peer_credentials(&a).expect("SO_PEERCRED");
        assert_eq!(c.uid, nix::unistd::getuid().as_raw());
        assert_eq!(c.gids[0], nix::unistd::getgid().as_raw());
    }
}
