//! A model file whose length fields or shapes claim gigabytes is refused before anything is
//! allocated for them: a counting global allocator (`stats_alloc`, which holds the unsafe code)
//! measures every load. Runs without the test harness so no other thread allocates meanwhile.

#[path = "malformed/model_bytes.rs"]
mod model_bytes;

use decoder::model::{FileError, ModelKind, TrainedModel};
use model_bytes::{join, join_claiming, split, valid_file};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Most bytes a refused load may allocate: its metadata parse, a few times the file's size.
const BUDGET: usize = 256 * 1024;

/// `meta` changed by `change` (on its JSON value).
fn edit(meta: &[u8], change: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let mut v: serde_json::Value = serde_json::from_slice(meta).expect("metadata is JSON");
    change(&mut v);
    serde_json::to_vec(&v).expect("JSON")
}

/// A ResDD of `hidden` width and `modules` modules, its tensor list to match.
fn resdd(v: &mut serde_json::Value, hidden: u64, modules: u64) {
    v["spec"]["resdd"]["hidden"] = hidden.into();
    v["spec"]["resdd"]["modules"] = modules.into();
    let n_in = v["n_inputs"].clone();
    let mut tensors = vec![serde_json::json!({"name": "w_in", "shape": [hidden, n_in]})];
    for l in 1..=modules {
        tensors.push(serde_json::json!({"name": format!("w_mod.{l}"), "shape": [hidden, hidden]}));
    }
    tensors.push(serde_json::json!({"name": "w_out", "shape": [5, hidden]}));
    v["tensors"] = tensors.into();
}

/// Loads `bytes`, returns the error and the bytes allocated meanwhile.
fn refused(what: &str, bytes: &[u8]) -> (FileError, usize) {
    let region = Region::new(GLOBAL);
    let result = TrainedModel::from_bytes(bytes, None);
    let allocated = region.change().bytes_allocated;
    let err = match result {
        Ok(_) => panic!("{what}: loaded"),
        Err(e) => e,
    };
    assert!(
        allocated < BUDGET,
        "{what}: {allocated} bytes allocated before refusing: {err}"
    );
    println!("{what}: refused after {allocated} bytes allocated: {err}");
    (err, allocated)
}

fn main() {
    let file = valid_file(ModelKind::ResDd);
    let p = split(&file);
    let claims: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "body length 2^40",
            join_claiming(&p.meta, &p.data, p.meta.len() as u64, Some(1 << 40)),
            "header says 1099511627776 body bytes",
        ),
        (
            "metadata length 2^40",
            join_claiming(&p.meta, &p.data, 1 << 40, None),
            "metadata length 1099511627776 exceeds",
        ),
        (
            "hidden width 2^40",
            join(&edit(&p.meta, |v| resdd(v, 1 << 40, 2)), &p.data),
            "must be in 1..=4096, got 1099511627776",
        ),
        (
            // Width and module count each at their limit: 64 · 4096² weights, 8.6 GB.
            "8.6 GB of weights within every per-field limit",
            join(&edit(&p.meta, |v| resdd(v, 4096, 64)), &p.data),
            "the tensors need 8591147264",
        ),
        (
            "a tensor shape of 2^40 elements",
            join(
                &edit(&p.meta, |v| {
                    v["tensors"][0]["shape"][0] = (1u64 << 40).into()
                }),
                &p.data,
            ),
            "wrong shape for w_in",
        ),
    ];
    for (what, bytes, expected) in &claims {
        let (err, _) = refused(what, bytes);
        assert!(err.to_string().contains(expected), "{what}: {err}");
    }
    println!("{} passed, 0 failed", claims.len());
}
