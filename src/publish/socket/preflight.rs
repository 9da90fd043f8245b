//! The checks [`Server::bind`](super::Server::bind) makes before it binds, callable
//! on their own: `check-config` and `run` ask them without binding anything, so a
//! config is refused for the same reasons, in the same words, before start-up.

use super::error::Error;
use super::privilege::PeerPolicy;
use std::io::ErrorKind;
use std::os::unix::fs::FileTypeExt;
use std::os::unix::net::UnixStream;
use std::path::Path;

/// Longest socket path in bytes: `sun_path` holds 108 bytes, the last one the
/// terminating NUL (unix(7)).
pub const MAX_SOCKET_PATH_BYTES: usize = 107;

/// What is at a socket path that can be bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathState {
    /// Nothing: bind creates the socket.
    Free,
    /// A socket nobody listens on (a daemon that was killed): bind replaces it.
    Stale,
}

/// Checks a socket path as `bind` will meet it: its length, its directory, and what
/// is there now.
///
/// # Errors
/// [`Error::PathTooLong`], [`Error::NoDirectory`], [`Error::NotASocket`] (a file,
/// a directory or a symbolic link is never replaced), [`Error::InUse`] (a live
/// socket: another daemon), [`Error::Io`] when the path cannot be inspected.
pub fn inspect_socket_path(path: &Path) -> Result<PathState, Error> {
    let bytes = path.as_os_str().len();
    if bytes > MAX_SOCKET_PATH_BYTES {
        return Err(Error::PathTooLong {
            path: path.to_path_buf(),
            bytes,
            max: MAX_SOCKET_PATH_BYTES,
        });
    }
    let dir = socket_dir(path);
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(Error::NoDirectory {
                path: path.to_path_buf(),
                dir: dir.to_path_buf(),
                problem: "is not a directory",
            })
        }
        Err(e) if matches!(e.kind(), ErrorKind::NotFound | ErrorKind::NotADirectory) => {
            return Err(Error::NoDirectory {
                path: path.to_path_buf(),
                dir: dir.to_path_buf(),
                problem: "does not exist",
            })
        }
        Err(source) => {
            return Err(Error::Io {
                path: dir.to_path_buf(),
                op: "inspect the socket's directory",
                source,
            })
        }
    }
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_socket() => match UnixStream::connect(path) {
            Ok(_) => Err(Error::InUse {
                path: path.to_path_buf(),
            }),
            Err(e) if e.kind() == ErrorKind::ConnectionRefused => Ok(PathState::Stale),
            Err(source) => Err(Error::Io {
                path: path.to_path_buf(),
                op: "check whether the existing socket is live",
                source,
            }),
        },
        Ok(meta) => {
            let t = meta.file_type();
            let kind = if t.is_dir() {
                "a directory"
            } else if t.is_symlink() {
                "a symbolic link"
            } else if t.is_file() {
                "a regular file"
            } else {
                "a device, FIFO or other special file"
            };
            Err(Error::NotASocket {
                path: path.to_path_buf(),
                kind,
            })
        }
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(PathState::Free),
        Err(source) => Err(Error::Io {
            path: path.to_path_buf(),
            op: "inspect the socket path",
            source,
        }),
    }
}

/// The directory the socket file is created in (`.` for a bare file name).
pub fn socket_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Whether this process may create the socket file in `dir` (write and search
/// permission; always true for root).
pub fn dir_writable(dir: &Path) -> bool {
    use nix::unistd::{access, AccessFlags};
    access(dir, AccessFlags::W_OK | AccessFlags::X_OK).is_ok()
}

/// The id of the group the socket is given to.
///
/// # Errors
/// [`Error::UnknownGroup`] when there is no such group, [`Error::GroupLookup`] when
/// the group database cannot be read.
pub fn lookup_group(group: &str) -> Result<nix::unistd::Gid, Error> {
    match nix::unistd::Group::from_name(group) {
        Ok(Some(g)) => Ok(g.gid),
        Ok(None) => Err(Error::UnknownGroup {
            group: group.to_string(),
        }),
        Err(source) => Err(Error::GroupLookup {
            group: group.to_string(),
            source,
        }),
    }
}

/// The privileged users and groups of `socket.privileged`, names or numeric ids,
/// resolved to ids.
///
/// # Errors
/// [`Error::UnknownPeer`] naming the first that does not resolve.
pub fn resolve_peers(users: &[String], groups: &[String]) -> Result<PeerPolicy, Error> {
    let unknown = |kind: &'static str, name: &str, reason: String| Error::UnknownPeer {
        kind,
        name: name.to_string(),
        reason,
    };
    let mut policy = PeerPolicy::default();
    for u in users {
        let uid = match u.parse::<u32>() {
            Ok(id) => id,
            Err(_) => match nix::unistd::User::from_name(u) {
                Ok(Some(user)) => user.uid.as_raw(),
                Ok(None) => return Err(unknown("user", u, "no such user".to_string())),
                Err(e) => return Err(unknown("user", u, format!("cannot be looked up: {e}"))),
            },
        };
        policy.users.push(uid);
    }
    for g in groups {
        let gid = match g.parse::<u32>() {
            Ok(id) => id,
            Err(_) => match nix::unistd::Group::from_name(g) {
                Ok(Some(group)) => group.gid.as_raw(),
                Ok(None) => return Err(unknown("group", g, "no such group".to_string())),
                Err(e) => return Err(unknown("group", g, format!("cannot be looked up: {e}"))),
            },
        };
        policy.groups.push(gid);
    }
    Ok(policy)
}

/// Whether this process may give a file it owns to group `gid` (`chown` to a
/// group: root, or a member of it).
pub fn may_use_group(gid: nix::unistd::Gid) -> bool {
    nix::unistd::geteuid().is_root()
        || nix::unistd::getegid() == gid
        || nix::unistd::getgroups().is_ok_and(|gs| gs.contains(&gid))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_at_the_path_decides() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.sock");
        assert_eq!(inspect_socket_path(&p).unwrap(), PathState::Free);
        // A socket nobody listens on.
        drop(std::os::unix::net::UnixListener::bind(&p).unwrap());
        assert_eq!(inspect_socket_path(&p).unwrap(), PathState::Stale);
        std::fs::remove_file(&p).unwrap();
        let live = std::os::unix::net::UnixListener::bind(&p).unwrap();
        assert!(matches!(inspect_socket_path(&p), Err(Error::InUse { .. })));
        drop(live);
        std::fs::remove_file(&p).unwrap();
        std::fs::create_dir(&p).unwrap();
        let e = inspect_socket_path(&p).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("s.sock: is a directory, not a socket; refusing to replace it"),
            "{e}"
        );
        std::fs::remove_dir(&p).unwrap();
        std::fs::write(&p, "x").unwrap();
        assert!(matches!(
            inspect_socket_path(&p),
            Err(Error::NotASocket {
                kind: "a regular file",
                ..
            })
        ));
        let e = inspect_socket_path(&dir.path().join("s.sock/x.sock")).unwrap_err();
        assert!(e.to_string().contains("is not a directory"), "{e}");
        let e = inspect_socket_path(&dir.path().join("missing/x.sock")).unwrap_err();
        assert!(
            e.to_string().contains("x.sock: the socket's directory ")
                && e.to_string().ends_with("/missing does not exist"),
            "{e}"
        );
    }

    #[test]
    fn a_path_longer_than_sun_path_is_refused_before_anything_else() {
        let ok = format!("/{}", "a".repeat(MAX_SOCKET_PATH_BYTES - 1));
        assert_eq!(
            inspect_socket_path(Path::new(&ok)).unwrap(),
            PathState::Free
        );
        let long = format!("/{}", "a".repeat(MAX_SOCKET_PATH_BYTES));
        let e = inspect_socket_path(Path::new(&long)).unwrap_err();
        assert!(
            e.to_string().ends_with(
                "socket path is 108 bytes, more than the 107 a Unix socket address holds"
            ),
            "{e}"
        );
    }

    #[test]
    fn groups_are_looked_up_by_name() {
        assert!(matches!(
            lookup_group("no-such-group-crowdtouch"),
            Err(Error::UnknownGroup { .. })
        ));
        let own = nix::unistd::getegid();
        if let Ok(Some(g)) = nix::unistd::Group::from_gid(own) {
            assert_eq!(lookup_group(&g.name).unwrap(), own);
        }
        assert!(may_use_group(own));
    }

    #[test]
    fn privileged_peers_resolve_by_name_or_id() {
        let p = resolve_peers(
            &["root".to_string(), "1234".to_string()],
            &["0".to_string()],
        )
        .unwrap();
        assert_eq!((p.users, p.groups), (vec![0, 1234], vec![0]));
        let e = resolve_peers(&["no-such-user-crowdtouch".to_string()], &[]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "user `no-such-user-crowdtouch` in socket.privileged.users: no such user"
        );
        let e = resolve_peers(&[], &["no-such-group-crowdtouch".to_string()]).unwrap_err();
        assert!(e.to_string().contains("socket.privileged.groups"), "{e}");
    }
}
