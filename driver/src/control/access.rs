//! Who is on the other end of a connection, and who may use the socket: root, the daemon's
//! own user and members of the configured group (SO_PEERCRED, checked before anything is read).

use std::fs;
use std::os::unix::net::UnixStream;

use super::ControlError;

/// Who is on the other end of a connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Peer {
    /// Effective user id.
    pub uid: u32,
    /// Effective group id.
    pub gid: u32,
    /// Process id.
    pub pid: i32,
}

/// Who may connect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccessPolicy {
    /// The daemon's user id.
    pub daemon_uid: u32,
    /// The allowed group's id, if any.
    pub group_gid: Option<u32>,
}

impl AccessPolicy {
    /// Whether `peer` may use the socket; `supplementary` lists the peer's extra groups.
    pub fn allows(&self, peer: &Peer, supplementary: &[u32]) -> bool {
        peer.uid == 0
            || peer.uid == self.daemon_uid
            || self
                .group_gid
                .is_some_and(|g| peer.gid == g || supplementary.contains(&g))
    }

    /// Whether `peer` may use the socket, reading its supplementary groups from `/proc` only
    /// when its user and primary group do not settle it.
    pub fn admits(&self, peer: &Peer) -> bool {
        self.allows(peer, &[])
            || (self.group_gid.is_some() && self.allows(peer, &supplementary_groups(peer.pid)))
    }
}

/// The id of group `name`, from `/etc/group`.
pub fn group_id(name: &str) -> Result<u32, ControlError> {
    let text = fs::read_to_string("/etc/group").unwrap_or_default();
    text.lines()
        .filter_map(|l| {
            let mut it = l.split(':');
            let n = it.next()?;
            let _pw = it.next()?;
            let gid = it.next()?.parse::<u32>().ok()?;
            (n == name).then_some(gid)
        })
        .next()
        .ok_or_else(|| ControlError::NoSuchGroup(name.to_owned()))
}

/// The supplementary groups of process `pid`, from `/proc/PID/status` (empty if unknown).
fn supplementary_groups(pid: i32) -> Vec<u32> {
    fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines().find_map(|l| l.strip_prefix("Groups:")).map(|g| {
                g.split_whitespace()
                    .filter_map(|x| x.parse().ok())
                    .collect()
            })
        })
        .unwrap_or_default()
}

/// The peer's credentials of a connected stream.
pub fn peer_of(stream: &UnixStream) -> std::io::Result<Peer> {
    let c = rustix::net::sockopt::socket_peercred(stream)?;
    Ok(Peer {
        uid: c.uid.as_raw(),
        gid: c.gid.as_raw(),
        pid: c.pid.as_raw_nonzero().get(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn policy_allows_root_owner_and_group_members_only() {
        let p = AccessPolicy {
            daemon_uid: 1000,
            group_gid: Some(50),
        };
        let peer = |uid, gid| Peer { uid, gid, pid: 1 };
        assert!(p.allows(&peer(0, 0), &[]));
        assert!(p.allows(&peer(1000, 1000), &[]));
        assert!(p.allows(&peer(1001, 50), &[]));
        assert!(p.allows(&peer(1001, 1001), &[7, 50]));
        assert!(!p.allows(&peer(1001, 1001), &[7]));
        let no_group = AccessPolicy {
            group_gid: None,
            ..p
        };
        assert!(!no_group.allows(&peer(1001, 50), &[50]));
    }

    #[test]
    fn unknown_group_is_an_error() {
        assert!(matches!(
            group_id("no-such-group-handstack"),
            Err(ControlError::NoSuchGroup(_))
        ));
        assert_eq!(group_id("root").unwrap(), 0);
    }
}
