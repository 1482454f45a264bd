//! The calibration's recording loop, over any transport and any clock: the real command runs
//! it on SocketCAN and the wall clock, the test on the in-memory bus and a virtual clock with
//! the simulated patient stepped by the clock.
//!
//! Every tick (10 ms): take every frame received into the log and the level trace; advance
//! the sequencer; on a phase change send the cue at once (else every 100 ms); when a trial's
//! RELAX ends, place it on the recording, check it, keep it or repeat it at once.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use decoder::dsp::ChainConfig;
use decoder::session::{Recording, Trial, TrialKind};
use hand_dbc::CanFrame;

use super::check::{check_trial, WARMUP_US};
use super::cue::CueSender;
use super::error::CalibrateError;
use super::output::Output;
use super::placement::{mean_level, place};
use super::protocol::Protocol;
use super::recorder::Recorder;
use super::resume_check::{check_age, check_rest, REST_CHECK_US};
use super::sequencer::{Event, HoldTimes, Phase, Sequencer};
use super::store::Store;

/// The loop's period, µs.
pub const TICK_US: u64 = 10_000;
/// The cue's period on the bus, µs (10 Hz).
pub const CUE_PERIOD_US: u64 = 100_000;

/// The bus the calibration cues on and records.
pub trait Transport {
    /// Sends one frame.
    fn send(&mut self, frame: &CanFrame) -> Result<(), CalibrateError>;
    /// The next frame received and its receive time (µs, the log's time base), or `None`
    /// when nothing is waiting.
    fn receive(&mut self) -> Result<Option<(CanFrame, u64)>, CalibrateError>;
}

/// The caller's clock, on the transport's time base.
pub trait Pace {
    /// Now, µs.
    fn now_us(&mut self) -> u64;
    /// Returns at `t_us` (the wall clock sleeps; a virtual clock steps the simulation).
    fn wait_until(&mut self, t_us: u64);
}

/// What the recording is to do.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The protocol (with `resume`: the one in the directory is used, this must equal it
    /// when given).
    pub protocol: Option<Protocol>,
    /// The output directory.
    pub dir: PathBuf,
    /// The interface name written in the log.
    pub iface: String,
    /// The session's chain (channels, rate, mains).
    pub chain: ChainConfig,
    /// Continue the calibration in `dir`.
    pub resume: bool,
    /// With `resume`: a session that started longer ago than this (minutes) is refused.
    pub max_resume_age_min: u64,
    /// With `resume`: go on although the live rest pattern differs from the session's.
    pub force_rest_mismatch: bool,
}

/// One attempt that failed its check.
#[derive(Debug, Clone, PartialEq)]
pub struct Repeat {
    /// The trial (as the session names it).
    pub trial: Trial,
    /// Its attempt (0 = first).
    pub attempt: u32,
    /// Why.
    pub reasons: Vec<String>,
}

/// What the recording did.
#[derive(Debug, Clone, Default)]
pub struct Recorded {
    /// Trials kept in the session.
    pub kept: usize,
    /// Attempts repeated, in order.
    pub repeats: Vec<Repeat>,
    /// Measured reaction times of the kept contractions, µs.
    pub reactions_us: Vec<u64>,
    /// Frames logged (received and sent) in this run.
    pub frames: u64,
}

/// The running calibration: everything the loop's steps share.
struct Run<'a, T: Transport> {
    bus: &'a mut T,
    rec: Recorder,
    store: Store,
    seq: Sequencer,
    cues: CueSender,
    out: &'a mut Output,
    next_cue_us: u64,
    rest_level: Option<f64>,
    done: Recorded,
}

/// Runs the cued recording to the end of the protocol (the session then complete on disk),
/// or to Ctrl-C (`stop`), or to a trial failing every attempt; either way the kept trials and
/// the log are on disk.
pub fn record_session(
    bus: &mut impl Transport,
    clock: &mut impl Pace,
    plan: &Plan,
    out: &mut Output,
    stop: &AtomicBool,
) -> Result<Recorded, CalibrateError> {
    let (store, protocol) = if plan.resume {
        Store::resume(&plan.dir, plan.chain.clone(), plan.protocol.as_ref())?
    } else {
        let p = plan.protocol.clone().unwrap_or_default();
        (Store::create(&plan.dir, plan.chain.clone(), &p)?, p)
    };
    let settings = plan.chain.validate()?;
    let resumed = if plan.resume {
        Some(old_recording(&store)?)
    } else {
        None
    };
    if let Some(r) = &resumed {
        check_age(
            r.time_us.first().copied(),
            clock.now_us(),
            plan.max_resume_age_min,
        )?;
    }
    let mut rec = Recorder::open(&plan.dir, &plan.iface, &settings, resumed)?;
    if plan.resume {
        rest_at_resume(bus, clock, &mut rec, &store, plan, out, stop)?;
    }
    let now = clock.now_us();
    let seq = Sequencer::new(&protocol, store.kept(), now);
    let mut run = Run {
        bus,
        rec,
        store,
        seq,
        cues: CueSender::new(),
        out,
        next_cue_us: now,
        rest_level: None,
        done: Recorded::default(),
    };
    if run.store.kept() > 0 {
        let k = run.store.kept();
        run.out
            .say(&format!("resuming after trial {k}: {k} trial(s) kept"));
    }
    let first = run.seq.cue(now);
    run.on_event(Event::Phase(first), now)?;
    run.run(clock, stop)?;
    run.done.kept = run.store.kept();
    run.done.frames = run.rec.frames();
    Ok(run.done)
}

/// Before the first cue of a resumed calibration: [`REST_CHECK_US`] of the patient relaxed,
/// recorded (into the log too) and compared with the session's kept rest trials
/// ([`check_rest`]); refused when the pattern differs, unless `--force-rest-mismatch`.
fn rest_at_resume(
    bus: &mut impl Transport,
    clock: &mut impl Pace,
    rec: &mut Recorder,
    store: &Store,
    plan: &Plan,
    out: &mut Output,
    stop: &AtomicBool,
) -> Result<(), CalibrateError> {
    out.say(&format!(
        "resuming: keep the patient relaxed for {} s while the rest level is compared with the \
         session's",
        REST_CHECK_US / 1_000_000
    ));
    let from = clock.now_us();
    let end = from + REST_CHECK_US;
    loop {
        while let Some((f, t)) = bus.receive()? {
            rec.on_frame(&f, t)?;
        }
        let now = clock.now_us();
        if stop.load(Ordering::Relaxed) {
            rec.flush()?;
            return Err(CalibrateError::Interrupted {
                dir: store.dir().display().to_string(),
                kept: store.kept(),
                next: store.kept() + 1,
            });
        }
        if now >= end {
            break;
        }
        clock.wait_until((now + TICK_US).min(end));
    }
    rec.flush()?;
    let said = check_rest(
        rec.recording(),
        &store.meta,
        (from + WARMUP_US, end),
        plan.force_rest_mismatch,
    )?;
    out.say(&said);
    Ok(())
}

/// The EMG of the log a resumed calibration continues (empty when the log holds none).
fn old_recording(store: &Store) -> Result<Recording, CalibrateError> {
    let path = store.meta.recording_path(store.dir());
    match Recording::load(&store.meta, store.dir()) {
        Ok(r) => Ok(r),
        Err(_) if !path.exists() || std::fs::metadata(&path).is_ok_and(|m| m.len() == 0) => {
            Ok(super::recorder::empty_recording(store.meta.chain.channels))
        }
        Err(e) => Err(e.into()),
    }
}

impl<T: Transport> Run<'_, T> {
    fn run(&mut self, clock: &mut impl Pace, stop: &AtomicBool) -> Result<(), CalibrateError> {
        loop {
            self.drain()?;
            let now = clock.now_us();
            if stop.load(Ordering::Relaxed) {
                let ev = self.seq.abort(now);
                self.on_event(ev, now)?;
                self.rec.flush()?;
                return Err(CalibrateError::Interrupted {
                    dir: self.store.dir().display().to_string(),
                    kept: self.store.kept(),
                    next: self.store.kept() + 1,
                });
            }
            while let Some(ev) = self.seq.advance(now) {
                self.on_event(ev, now)?;
            }
            if self.seq.finished() {
                self.rec.flush()?;
                return Ok(());
            }
            if now >= self.next_cue_us {
                self.send_cue(now)?;
            }
            self.out
                .tick(&self.seq.cue(now), self.rec.level(), self.rest_level);
            clock.wait_until(now + TICK_US);
        }
    }

    /// Every frame waiting into the log and the trace.
    fn drain(&mut self) -> Result<(), CalibrateError> {
        while let Some((f, t)) = self.bus.receive()? {
            self.rec.on_frame(&f, t)?;
        }
        Ok(())
    }

    fn send_cue(&mut self, now: u64) -> Result<(), CalibrateError> {
        let frame = self.cues.frame(&self.seq.cue(now));
        self.bus.send(&frame)?;
        // The log records the cues too: the session's own account of what was asked when.
        self.rec.on_frame(&frame, now)?;
        self.next_cue_us = now + CUE_PERIOD_US;
        Ok(())
    }

    fn on_event(&mut self, ev: Event, now: u64) -> Result<(), CalibrateError> {
        match ev {
            Event::Phase(cue) => {
                self.send_cue(now)?;
                self.out.phase(&cue);
                if cue.phase == Phase::Aborted && !self.seq.awaiting_check() {
                    self.rec.flush()?;
                }
                Ok(())
            }
            Event::CheckDue(hold) => {
                let next = self.check(&hold, now)?;
                self.on_event(next, now)
            }
        }
    }

    /// Places and checks the trial whose RELAX just ended; the sequencer's next event.
    fn check(&mut self, hold: &HoldTimes, now: u64) -> Result<Event, CalibrateError> {
        let (movement, repetition) = self.seq.trials()[hold.trial];
        let (start_us, end_us, reaction) =
            place(hold, movement.kind, self.rec.trace(), self.rest_level);
        let trial = Trial {
            id: hold.trial as u32 + 1,
            finger: movement.finger,
            kind: movement.kind,
            repetition: repetition + 1,
            start_us,
            end_us,
        };
        self.rec.flush()?;
        let verdict = check_trial(self.rec.recording(), &self.store.meta, trial)?;
        let reasons = verdict.reasons;
        self.out.verdict(&trial, hold.attempt, reaction, &reasons);
        if reasons.is_empty() {
            if trial.kind == TrialKind::Rest {
                self.rest_level =
                    mean_level(self.rec.trace(), start_us, end_us).or(self.rest_level);
            }
            self.done.reactions_us.extend(reaction);
            self.store.keep(trial)?;
            return Ok(self.after_pass(verdict.weaker_kept, now));
        }
        self.done.repeats.push(Repeat {
            trial,
            attempt: hold.attempt,
            reasons: reasons.clone(),
        });
        let ev = self.seq.failed(now);
        if self.seq.finished() {
            self.send_cue(now)?;
            self.rec.flush()?;
            return Err(CalibrateError::TrialFailed {
                trial: trial.to_string(),
                attempts: hold.attempt + 1,
                reason: reasons.join("; "),
            });
        }
        Ok(ev)
    }

    /// The next event after a kept attempt: the next trial, or first a kept repetition this
    /// attempt showed much weaker (a weak first repetition is only seen against a later one).
    fn after_pass(&mut self, weaker: Vec<(u32, String)>, now: u64) -> Event {
        let Some((id, why)) = weaker.into_iter().next() else {
            return self.seq.passed(now);
        };
        let Some(old) = self.store.meta.trials.iter().find(|t| t.id == id).copied() else {
            return self.seq.passed(now);
        };
        self.out.verdict(&old, 0, None, std::slice::from_ref(&why));
        self.done.repeats.push(Repeat {
            trial: old,
            attempt: 0,
            reasons: vec![why],
        });
        self.seq.passed_then_redo(now, id as usize - 1)
    }
}
