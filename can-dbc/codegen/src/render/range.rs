//! Range checks of raw values, and raw-to-`f64` conversion.

use crate::model::Signal;

/// A statement refusing raw value `v` (of the signal's raw type) outside the DBC raw range;
/// emits only the comparisons the type does not already guarantee (nothing if none).
/// `message` is the expression naming the message (`message` when a local of that name).
pub(super) fn raw_check(s: &Signal, v: &str, message: &str) -> String {
    let ty = s.raw_ty;
    let below = s.raw_min > ty.min();
    let above = s.raw_max < ty.max();
    let cond = match (below, above) {
        (true, true) => format!("!({}..={}).contains(&{v})", s.raw_min, s.raw_max),
        (true, false) => format!("{v} < {}", s.raw_min),
        (false, true) => format!("{v} > {}", s.raw_max),
        (false, false) => return String::new(),
    };
    let raw = if ty.name() == "u64" {
        format!("{v} as i64")
    } else {
        format!("i64::from({v})")
    };
    let message = if message == "message" {
        "message".to_string()
    } else {
        format!("message: {message}")
    };
    format!(
        "if {cond} {{ return Err(CodecError::RawOutOfRange {{ {message}, signal: {:?}, raw: {raw}, \
         min: {}, max: {} }}); }}\n",
        s.name, s.raw_min, s.raw_max
    )
}

/// The raw expression `v` as `f64` (`as` for 64-bit types, which have no lossless `From`).
pub(super) fn raw_to_f64(s: &Signal, v: &str) -> String {
    if s.raw_ty.is_64() {
        format!("({v} as f64)")
    } else {
        format!("f64::from({v})")
    }
}
