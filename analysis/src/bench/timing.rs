//! Wall-clock cost of one call: the minimum over batches after a warm-up
//! (the DiffEqDevTools convention: the minimum is the least noisy estimate
//! of the cost).

use std::time::Instant;

/// Minimum time per call of `f`, seconds, over 5 batches of ≈ 0.2 ms each
/// after a warm-up ([`time_min_of`]).
pub fn time_min(f: impl FnMut()) -> f64 {
    time_min_of(5, f)
}

/// Minimum time per call of `f`, seconds, over `batches` batches (at least
/// one) of ≈ 0.2 ms each: `f` runs once to warm up, once more to size the
/// batch (`k = ⌈0.2 ms / once⌉`, 1 … 100 000 calls), then `k` times per batch.
pub fn time_min_of(batches: usize, mut f: impl FnMut()) -> f64 {
    f();
    let t0 = Instant::now();
    f();
    let once = t0.elapsed().as_secs_f64().max(1e-9);
    let k = ((2e-4 / once).ceil() as usize).clamp(1, 100_000);
    let mut best = f64::INFINITY;
    for _ in 0..batches.max(1) {
        let t = Instant::now();
        for _ in 0..k {
            f();
        }
        best = best.min(t.elapsed().as_secs_f64() / k as f64);
    }
    best
}
