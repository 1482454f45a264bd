//! Issue 30, item 7: handd as the board runs it, not as root. The install of README.md
//! ("Installing handd on the board", step 2) is made under the scratch directory: the config
//! directory and the state directory owned by the user `handstack` with mode 0750, the config
//! and the model 0640, the runtime directory (the unit's RuntimeDirectory=, mode 0750) for the
//! socket. handd runs as `handstack` with the unit's limits (LimitRTPRIO=80,
//! LimitMEMLOCK=infinity); handctl runs as a technician, `tech`, whose group is `handstack`.
//! `handctl tune`, `deploy` and `rollback` must all work: each makes handd rewrite its config
//! (a temporary file beside it, renamed over it) and deploy copies the model into the state
//! directory. scripts/vm/run adds both users to the initramfs's /etc/passwd and /etc/group.

use std::os::unix::fs::{chown, MetadataExt, PermissionsExt};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use decoder::model::TrainedModel;
use driver::startup::fingerprint;
use handstack_tests::vcan::procs::{handsim, Layout};
use handstack_tests::vcan::{Monitor, TestConfig, VcanEnv};

use super::arming::Armed;
use super::restart::wait_active_after;

/// uid and primary gid of `name`, from /etc/passwd.
fn user(name: &str) -> (u32, u32) {
    let text = std::fs::read_to_string("/etc/passwd").unwrap_or_default();
    text.lines()
        .find_map(|l| {
            let f: Vec<&str> = l.split(':').collect();
            (f.len() >= 4 && f[0] == name).then(|| (f[2].parse().ok(), f[3].parse().ok()))
        })
        .and_then(|(u, g)| Some((u?, g?)))
        .unwrap_or_else(|| {
            panic!(
                "no user {name:?} in /etc/passwd: scripts/vm/run adds `handstack` (990) and \
                 `tech` (991, group handstack); elsewhere add them (README, install step 2)"
            )
        })
}

/// `install -d -o UID -g GID -m MODE DIR`.
fn install_dir(dir: &Path, owner: (u32, u32), mode: u32) {
    std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("mkdir {}: {e}", dir.display()));
    own(dir, owner, mode);
}

/// chown and chmod.
fn own(path: &Path, (uid, gid): (u32, u32), mode: u32) {
    chown(path, Some(uid), Some(gid)).unwrap_or_else(|e| panic!("chown {}: {e}", path.display()));
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
        .unwrap_or_else(|e| panic!("chmod {}: {e}", path.display()));
}

/// `handctl ARGS --socket SOCKET` as the technician; panics with its output unless it succeeds.
fn handctl_as(env: &VcanEnv, tech: (u32, u32), socket: &Path, args: &[&str]) -> String {
    let out = Command::new(env.bin("handctl"))
        .uid(tech.0)
        .gid(tech.1)
        .args(args)
        .args(["--socket", &socket.display().to_string()])
        .output()
        .expect("handctl runs");
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.status.success(),
        "handctl {} as the technician failed ({}): {said}",
        args.join(" "),
        out.status
    );
    said
}

/// The model handd runs, by `handctl status`.
fn running_id(cfg: &TestConfig, env: &VcanEnv) -> String {
    cfg.status(env).model.map(|m| m.id).unwrap_or_default()
}

#[test]
fn field_handd_as_the_handstack_user_tunes_deploys_and_rolls_back() {
    let env = VcanEnv::get();
    let model = super::calibrated_model(&env).to_path_buf();
    let hs = user("handstack");
    let tech = user("tech");
    assert_eq!(tech.1, hs.1, "the technician's group is handstack");
    let root = env.scratch("service-user");
    let (etc, var, run, home) = (
        root.join("etc/handstack"),
        root.join("var/lib/handstack"),
        root.join("run/handstack"),
        root.join("home/tech"),
    );
    // README step 2, and the unit's RuntimeDirectory=handstack, RuntimeDirectoryMode=0750.
    install_dir(&etc, hs, 0o750);
    install_dir(&var, hs, 0o750);
    install_dir(&run, hs, 0o750);
    install_dir(&home, (tech.0, tech.1), 0o755);
    let installed = var.join("model.hsm");
    std::fs::copy(&model, &installed).expect("install the model");
    own(&installed, hs, 0o640);
    let layout = Layout {
        config: etc.join("handd.toml"),
        state_dir: var.clone(),
        socket: run.join("handctl.sock"),
        group: "handstack".into(),
    };
    let cfg = TestConfig::write_installed(&env, &layout, &installed, 100);
    own(&cfg.path, hs, 0o640);
    // The technician's new model, in the technician's home (readable by handstack, which
    // reads it): the calibrated one with its rest levels scaled by 1 ppm, another file.
    let bytes = std::fs::read(&model).expect("the calibrated model");
    let m = TrainedModel::from_bytes(&bytes, None).expect("the calibrated model parses");
    let levels: Vec<f64> = m.rest_rms_uv().map_or(vec![1.0; m.n_channels()], |r| {
        r.iter().map(|v| v * (1.0 + 1e-6)).collect()
    });
    let second = home.join("second.hsm");
    m.clone()
        .with_rest_rms_uv(levels)
        .expect("rest levels")
        .save(&second)
        .expect("save the second model");
    own(&second, (tech.0, tech.1), 0o644);
    let (id_a, id_b) = (
        format!("{:08x}", fingerprint(&bytes)),
        format!(
            "{:08x}",
            fingerprint(&std::fs::read(&second).expect("the second model"))
        ),
    );
    // The unit's LimitRTPRIO=80 and LimitMEMLOCK=infinity, inherited by handd.
    use rustix::process::{setrlimit, Resource, Rlimit};
    setrlimit(
        Resource::Rtprio,
        Rlimit {
            current: Some(80),
            maximum: Some(80),
        },
    )
    .expect("RLIMIT_RTPRIO");
    setrlimit(
        Resource::Memlock,
        Rlimit {
            current: None,
            maximum: None,
        },
    )
    .expect("RLIMIT_MEMLOCK");

    let monitor = Monitor::start(&env.iface);
    let mut handd = cfg.start_as(&env, &root, "handd", Some(hs));
    let proc_status =
        std::fs::read_to_string(format!("/proc/{}/status", handd.pid())).unwrap_or_default();
    assert!(
        proc_status.lines().any(
            |l| l.starts_with("Uid:") && l.split_whitespace().nth(1) == Some(&hs.0.to_string())
        ),
        "handd does not run as handstack:\n{proc_status}"
    );
    let mut sim = handsim(&env, &root, "handsim", "sine", 15.0, &[]);
    wait_active_after(&monitor, 0, Duration::from_secs(10))
        .expect("handd as handstack never RUNNING");
    assert_eq!(running_id(&cfg, &env), id_a);

    handctl_as(
        &env,
        tech,
        &cfg.socket,
        &["tune", "--finger", "index", "--kf", "5"],
    );
    let saved = driver::Config::load(&cfg.path).expect("the tuned config loads");
    assert_eq!(
        saved.fingers.get(1).kf,
        5.0,
        "the config file holds the new kF"
    );

    handctl_as(
        &env,
        tech,
        &cfg.socket,
        &["deploy", &second.display().to_string(), "--yes"],
    );
    assert_eq!(
        running_id(&cfg, &env),
        id_b,
        "the deployed model does not run"
    );
    let deployed = driver::Config::load(&cfg.path).expect("the config after the deploy");
    assert!(
        deployed.model.starts_with(&var) && deployed.model.is_file(),
        "deploy did not install the model in the state directory: {}",
        deployed.model.display()
    );

    handctl_as(&env, tech, &cfg.socket, &["rollback"]);
    assert_eq!(
        running_id(&cfg, &env),
        id_a,
        "rollback did not bring the first model back"
    );
    let armed = Armed::time(|| {
        handctl_as(&env, tech, &cfg.socket, &["arm", "--force-rest-mismatch"]);
    });
    let resumed = wait_active_after(&monitor, armed.sent_us, Duration::from_secs(3))
        .expect("never ACTIVE after the rollback and arm");
    armed.check(
        "as handstack, after the rollback",
        resumed,
        &monitor.snapshot(),
    );

    // What handd wrote is handstack's, and the rewritten config keeps the install's mode.
    for (p, what) in [
        (cfg.path.clone(), "the rewritten config"),
        (deployed.model.clone(), "the deployed model"),
        (var.join(driver::persist::LATCH_FILE), "the latch file"),
        (var.join("audit.log"), "the audit log"),
    ] {
        let md = std::fs::metadata(&p).unwrap_or_else(|e| panic!("{what} {}: {e}", p.display()));
        println!(
            "as handstack: {what} {} owner {}:{} mode {:o}",
            p.display(),
            md.uid(),
            md.gid(),
            md.mode() & 0o7777
        );
        assert_eq!(md.uid(), hs.0, "{what} is not handstack's");
    }
    let mode = std::fs::metadata(&cfg.path).expect("the config").mode() & 0o7777;
    assert_eq!(
        mode, 0o640,
        "the rewritten config lost the install's mode 0640 (now {mode:o})"
    );
    let log = handd.output();
    assert!(
        !log.contains("ermission denied") && !log.contains("EACCES"),
        "handd as handstack was refused something:\n{log}"
    );
    println!("as handstack: tune, deploy ({id_b}) and rollback ({id_a}) by the technician");
    sim.kill();
    handd.kill();
}
