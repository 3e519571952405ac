//! Benchmark (to be written): prints its figures.
fn main() {}
