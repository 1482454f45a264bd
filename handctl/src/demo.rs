//! `handctl demo`: the whole system in one process over the in-memory bus (see
//! `driver::demo`), with live per-finger state on the terminal and the tracking scores at the
//! end.

use std::io::{IsTerminal, Write};

use driver::demo::{run_demo, DemoEvent, DemoOptions, DriveProfile, DrivesRecord, OutputLaw};
use driver::drive_config::DriveMode;
use driver::units::FINGER_NAMES;

use super::args::{DemoArgs, DemoDriveMode, DemoDrives, DemoLaw};
use super::error::CliError;
use super::progress::Progress;

/// The fingers' drives `--drives` and `--drive-mode` ask for; a mode without drives is refused.
fn drive_profile(a: &DemoArgs) -> Result<DriveProfile, CliError> {
    let mode = a.drive_mode.map(|m| match m {
        DemoDriveMode::Cst => DriveMode::Cst,
        DemoDriveMode::Csv => DriveMode::Csv,
        DemoDriveMode::Pv => DriveMode::Pv,
    });
    match (a.drives, mode) {
        (DemoDrives::Native, None) => Ok(DriveProfile::Native),
        (DemoDrives::Native, Some(_)) => Err(CliError::Usage(
            "demo: --drive-mode needs --drives cia402 (native fingers have no drive mode)".into(),
        )),
        (DemoDrives::Cia402, mode) => Ok(DriveProfile::Cia402(mode.unwrap_or(DriveMode::Cst))),
    }
}

/// `handctl demo`.
pub fn run(a: &DemoArgs) -> Result<(), CliError> {
    let drives = drive_profile(a)?;
    let opts = DemoOptions {
        seed: a.seed,
        fast: a.fast,
        track_s: a.seconds + 4.0,
        settle_s: 4.0,
        work_dir: a
            .dir
            .clone()
            .unwrap_or_else(|| std::env::temp_dir().join("handstack-demo")),
        plain: a.plain,
        mask_others: a.paper_masks,
        law: match a.law {
            DemoLaw::Shipped => OutputLaw::Shipped,
            DemoLaw::Paper => OutputLaw::Paper,
        },
        drives,
        ..DemoOptions::default()
    };
    let tty = std::io::stdout().is_terminal();
    let mut progress = Progress::new("resdd");
    let mut last_print = -1.0;
    let report = run_demo(&opts, |e| match e {
        DemoEvent::Phase(p) => {
            progress.finish_if_started();
            println!("== {p}");
        }
        DemoEvent::Epoch(r) => progress.epoch(&r),
        DemoEvent::Live {
            t_s,
            snapshot,
            target,
            tracked,
        } => {
            // On a terminal: one live block; in a pipe: a line a second.
            if !tty && t_s - last_print < 1.0 {
                return;
            }
            last_print = t_s;
            let fingers: Vec<String> = (0..5)
                .map(|f| {
                    format!(
                        "{} {:+.2}/{:+5.1}N",
                        &FINGER_NAMES[f][..2],
                        snapshot.setpoints[f].label,
                        snapshot.reported_force[f]
                    )
                })
                .collect();
            let line = format!(
                "t {t_s:5.1}s {:<7} target {target:+.2} index {tracked:+.2} | {}",
                snapshot.state.to_string(),
                fingers.join(" ")
            );
            if tty {
                print!("\r{line}  ");
                let _ = std::io::stdout().flush();
            } else {
                println!("{line}");
            }
        }
    })
    .map_err(|e| CliError::Usage(format!("demo: {e}")))?;
    if tty {
        println!();
    }
    println!(
        "calibration: {} trials in {}; model {} ({} epochs, {:.2} s)",
        report.trials,
        report.session_dir.display(),
        report.model_path.display(),
        report.epochs,
        report.train_ms as f64 / 1000.0
    );
    println!("model effort rays: {}", report.verification);
    println!(
        "tracking (index finger, sine amplitude 1, period 4 s, {} samples): RMSE {:.3}  MAPE {}  R² {:.3}",
        report.tracking.samples,
        report.tracking.rmse,
        report.tracking.mape.map_or("n/a".into(), |m| format!("{m:.1}%")),
        report.tracking.r2
    );
    println!("{}", selectivity(&report.tracking.mean_abs_label));
    println!(
        "output law {:?}: {}",
        a.law,
        motion(
            &report.tracking.mean_abs_velocity,
            &report.tracking.at_stop_s,
            &report.tracking.impacts,
            match drives {
                DriveProfile::Native => "velocity setpoint",
                // A drive's finger sends no FINGER_SETPOINT to read: the joint's own velocity.
                DriveProfile::Cia402(_) => "joint velocity",
            }
        )
    );
    if let Some(line) = drives_line(&report.tracking.drives) {
        println!("{line}");
    }
    println!(
        "daemon: latency p50 {} us p99 {} us, compute p50 {} us p99 {} us, deadline misses {}, state {}",
        report.tracking.end.latency.p50_us,
        report.tracking.end.latency.p99_us,
        report.tracking.end.compute.p50_us,
        report.tracking.end.compute.p99_us,
        report.tracking.end.counters.deadline_misses,
        report.tracking.end.state
    );
    Ok(())
}

/// The CiA 402 drives' line (None with native fingers).
fn drives_line(d: &DrivesRecord) -> Option<String> {
    (d.drives > 0).then(|| {
        format!(
            "CiA 402 drives: {} started by the daemon, all following their target {}; {} of {} \
             following at the end",
            d.drives,
            d.all_enabled_s.map_or("NEVER".to_string(), |t| format!(
                "{t:.2} s after the loop started"
            )),
            d.enabled_at_end,
            d.drives
        )
    })
}

/// The selectivity line: the mean |label| of every finger while the index tracks.
fn selectivity(mean_abs_label: &[f64; 5]) -> String {
    let fingers: Vec<String> = (0..5)
        .map(|f| format!("{} {:.3}", FINGER_NAMES[f], mean_abs_label[f]))
        .collect();
    format!(
        "selectivity (mean |label| per finger while the index tracks; others should stay near 0): {}",
        fingers.join(", ")
    )
}

/// The output law's line: per finger, the mean |velocity| (`velocity`: of what), the time at a
/// joint stop, and the impacts into a stop with the fastest.
fn motion(
    mean_abs_velocity: &[f64; 5],
    at_stop_s: &[f64; 5],
    impacts: &[(u64, f64); 5],
    velocity: &str,
) -> String {
    let fingers: Vec<String> = (0..5)
        .map(|f| {
            format!(
                "{} {:.2} rad/s, {:.1} s, {} at <= {:.2} rad/s",
                FINGER_NAMES[f], mean_abs_velocity[f], at_stop_s[f], impacts[f].0, impacts[f].1
            )
        })
        .collect();
    format!(
        "per finger: mean |{velocity}|, time at a joint stop, impacts into a stop: {}",
        fingers.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::{Cli, Command};
    use clap::Parser;

    fn profile(argv: &[&str]) -> Result<DriveProfile, CliError> {
        let cli = Cli::try_parse_from(argv).expect("parses");
        let Command::Demo(a) = &cli.command else {
            panic!("not the demo: {:?}", cli.command);
        };
        drive_profile(a)
    }

    #[test]
    fn the_drive_mode_defaults_to_cst_and_needs_drives() {
        assert_eq!(
            profile(&["handctl", "demo"]).expect("native"),
            DriveProfile::Native
        );
        assert_eq!(
            profile(&["handctl", "demo", "--drives", "cia402"]).expect("cst"),
            DriveProfile::Cia402(DriveMode::Cst)
        );
        assert_eq!(
            profile(&[
                "handctl",
                "demo",
                "--drives",
                "cia402",
                "--drive-mode",
                "csv"
            ])
            .expect("csv"),
            DriveProfile::Cia402(DriveMode::Csv)
        );
        assert_eq!(
            profile(&[
                "handctl",
                "demo",
                "--drives",
                "cia402",
                "--drive-mode",
                "pv"
            ])
            .expect("pv"),
            DriveProfile::Cia402(DriveMode::Pv)
        );
        assert!(matches!(
            profile(&["handctl", "demo", "--drive-mode", "csv"]),
            Err(CliError::Usage(m)) if m.contains("--drives cia402")
        ));
        assert!(Cli::try_parse_from(["handctl", "demo", "--drive-mode", "cyclic"]).is_err());
    }
}
