//! Model benchmarks (placeholder until the real ones land in this file).
fn main() {}
