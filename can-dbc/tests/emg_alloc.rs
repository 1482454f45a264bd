//! Proof that EMG frame decode, E2E check and sample reassembly never touch the heap per
//! frame: a counting global allocator (`stats_alloc`, which holds the unsafe code) around a
//! stream with lost frames, lost samples, reordering, duplicates and a gap. Runs without the
//! test harness so no other thread allocates while the region is measured.

use std::alloc::System;

use hand_dbc::e2e::{E2eChecker, E2eProtector, E2eStatus};
use hand_dbc::emg::{EmgAssembler, EmgConfig, EmgFrame};
use hand_dbc::messages::{self, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2};
use hand_dbc::CanFrame;
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    let profiles = [EmgSamplesG0::E2E, EmgSamplesG1::E2E, EmgSamplesG2::E2E];
    let mut tx = profiles.map(E2eProtector::new);
    let mut input: Vec<(CanFrame, u64)> = Vec::new();
    for k in 0..3000u64 {
        for (g, p) in tx.iter_mut().enumerate() {
            let mut data = [0u8; 8];
            data[2] = (k as u8).wrapping_mul(3);
            data[7] = g as u8;
            let mut frame =
                CanFrame::new_standard(0x100 + g as u16, &data).expect("valid EMG frame");
            p.protect(&mut frame).expect("right length");
            // Drop some frames, whole samples, and leave a 30 ms hole.
            let dropped = (k % 97 == 5 && g == 1) || k % 211 == 7 || (1500..1530).contains(&k);
            if !dropped {
                input.push((frame, k * 1000 + g as u64 * 50));
            }
        }
    }
    // A duplicate and a reordering.
    input.insert(10, input[9]);
    input.swap(20, 21);

    let mut checkers = profiles.map(|p| E2eChecker::try_new(p, 15).expect("valid"));
    let mut asm = EmgAssembler::try_new(EmgConfig::default()).expect("valid");
    let mut samples = 0u64;
    let mut e2e_errors = 0u64;

    let region = Region::new(GLOBAL);
    for (frame, t) in &input {
        let msg = messages::decode_frame(frame).expect("valid payload");
        let group = (frame.raw_id() - 0x100) as usize;
        if checkers[group].check_frame(Some(frame)) == E2eStatus::Error {
            e2e_errors += 1;
        }
        let f = EmgFrame::from_message(&msg).expect("EMG message");
        asm.push(&f, *t, &mut |_| samples += 1);
    }
    asm.flush(&mut |_| samples += 1);
    let stats = region.change();

    let st = asm.stats();
    assert_eq!(e2e_errors, 0);
    assert!(samples > 2900, "only {samples} samples");
    assert!(st.lost_samples > 10 && st.gaps == 1, "{st:?}");
    assert_eq!(
        (stats.allocations, stats.reallocations),
        (0, 0),
        "decode + E2E check + reassembly allocated: {stats:?}"
    );
    println!(
        "emg_alloc: {} frames, {samples} samples ({} bridged, {} gap), 0 allocations",
        input.len(),
        st.lost_samples,
        st.gaps
    );
    println!("emg_alloc: 1 passed, 0 failed");
}
