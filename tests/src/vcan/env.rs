//! Where the suite runs: the interface, the project's binaries and a scratch directory. Each
//! missing piece is a panic that says what is missing and how to get it; nothing is skipped.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The interface and the binaries of one suite run.
#[derive(Debug, Clone)]
pub struct VcanEnv {
    /// SocketCAN interface (`HANDSTACK_VCAN`, default `vcan0`).
    pub iface: String,
    /// Directory holding handd, handsim and handctl (`HANDSTACK_BIN_DIR`, default: the cargo
    /// profile directory this test binary was built into).
    pub bin_dir: PathBuf,
}

impl VcanEnv {
    /// The environment, checked: the interface exists and is up, the binaries exist.
    pub fn get() -> Self {
        let iface = std::env::var("HANDSTACK_VCAN").unwrap_or_else(|_| "vcan0".into());
        let dev = Path::new("/sys/class/net").join(&iface);
        assert!(
            dev.exists(),
            "vcan suite: CAN interface {iface:?} is missing. Run ./scripts/vm/run (boots a VM whose \
             kernel has vcan), or create it: sudo modprobe vcan && sudo ip link add dev {iface} \
             type vcan && sudo ip link set {iface} mtu 72 up"
        );
        let bin_dir = match std::env::var_os("HANDSTACK_BIN_DIR") {
            Some(d) => PathBuf::from(d),
            None => {
                let exe = std::env::current_exe().expect("the test binary's own path");
                // target/<triple>/<profile>/deps/vcan-HASH -> target/<triple>/<profile>
                exe.parent()
                    .and_then(Path::parent)
                    .map(Path::to_path_buf)
                    .expect("the test binary lies in a cargo deps directory")
            }
        };
        for b in ["handd", "handsim", "handctl"] {
            assert!(
                bin_dir.join(b).is_file(),
                "vcan suite: {} is missing: build the binaries into the same profile \
                 (cargo build --release -p driver -p handctl -p hand-model --bins) or set HANDSTACK_BIN_DIR",
                bin_dir.join(b).display()
            );
        }
        let env = Self { iface, bin_dir };
        env.link("up");
        env
    }

    /// can-utils' candump: next to the project's binaries (the VM) or /usr/bin (Debian's
    /// can-utils); a clear panic if neither has it.
    pub fn candump(&self) -> PathBuf {
        [
            self.bin_dir.join("candump"),
            PathBuf::from("/usr/bin/candump"),
        ]
        .into_iter()
        .find(|p| p.is_file())
        .unwrap_or_else(|| {
            panic!(
                "vcan suite: candump is missing: install can-utils (sudo apt-get install \
                     can-utils), or run ./scripts/vm/run, which puts it in the VM"
            )
        })
    }

    /// Path of one of the project's binaries.
    pub fn bin(&self, name: &str) -> PathBuf {
        self.bin_dir.join(name)
    }

    /// `ip link set IFACE up|down`; panics with ip's message if it fails.
    pub fn link(&self, updown: &str) {
        let out = Command::new("ip")
            .args(["link", "set", &self.iface, updown])
            .output()
            .expect("vcan suite: cannot run `ip` (iproute2 or busybox ip is needed)");
        assert!(
            out.status.success(),
            "ip link set {} {updown}: {}",
            self.iface,
            String::from_utf8_lossy(&out.stderr)
        );
    }

    /// A fresh scratch directory for one test.
    pub fn scratch(&self, test: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("vcan-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("scratch directory in the temp dir");
        d
    }
}
