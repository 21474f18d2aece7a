//! The kinks of the springs' `⟨s⟩(ξ)`: closed-form candidates where a
//! spring's arc structure changes, checked and located by the springs'
//! signatures, so that the quadrature's pieces end at them.

use super::spring;
use crate::model::exact;
use crate::model::float::{Float, Math};
use crate::model::liftoff::Shape;
use crate::model::root::{illinois, Probe};
use crate::model::scene::Drive;

/// Most pieces of the quadrature's first partition: two searched segments
/// cut by at most `KINK_SAMPLES + 1` kinks each (between the `KINK_SAMPLES + 2`
/// samples), and the sliding segment (21 ≤ 24, checked at compile time).
pub(super) const MAX_PIECES: usize = 24;
const _: () = assert!(2 * (KINK_SAMPLES as usize + 2) < MAX_PIECES);

/// Width (in units of π of the segment's `t`) to which a kink is bracketed:
/// one left that close to an interval end costs the Kronrod rule about
/// `|Δf'|·(10⁻⁵ π h)²`, which the adaptive bisection then resolves.
const KINK_RESOLUTION: f64 = 1e-5;

/// How much further each next look of [`kinks`] at a side of a
/// closed-form candidate goes when the previous one shows a code other than
/// the bracket's ([`KINK_CONFIRM_LOOKS`] looks: ½, 32 and 2048 times the
/// resolution). At a window-edge kink a slip reaches the lift-off; on one
/// side the stick and the slip that follow it are both short, the slip
/// below the signatures' 10⁻⁶ rad floor while the stick is not (the slip
/// shrinks quadratically), so a code without the slip shows in a layer up
/// to ~10⁻³ wide in `d` (seen: 1.1·10⁻³ at a = 1.02, b = 0.67, φ = −1.2,
/// V = 0.045) — the bisection would stop at that layer's edge instead.
const KINK_CONFIRM_FAR: f64 = 64.0;

/// Looks per side of a candidate ([`KINK_CONFIRM_FAR`]).
const KINK_CONFIRM_LOOKS: u32 = 3;

/// Points sampled per segment for changes of the arc structure, equally
/// spaced in `t` (plus one [`KINK_END`] from each end).
const KINK_SAMPLES: u32 = 8;

/// Distance (units of π in `t`) from the lift-off onset `ξ_a` of an extra
/// sample on each side of it: changes between it and the nearest regular
/// sample are searched too (a permanent spring just above the onset,
/// `d → a⁺`, changes its arc structure within `d − a ≈ 10⁻⁴` in some
/// scenes, inside the last `π/9` of the segment).
const KINK_END: f64 = 1e-4;

/// A segment `[l, r]` (ξ) to search for kinks.
pub(super) struct Search<'h, T> {
    pub(super) l: T,
    pub(super) r: T,
    /// Extra samples next to the lift-off onset at its left / right end.
    pub(super) ends: (bool, bool),
    /// Kink candidates in closed form (ξ, any order; [`kink_candidates`]).
    pub(super) hint: &'h [T],
    /// The drive's geometry at the velocity.
    pub(super) shape: &'h Shape<T>,
}

/// Most kink candidates kept ([`kink_candidates`]).
pub(super) const MAX_CANDIDATES: usize = 16;

/// Points on `θ_c ∈ (0, π)` where [`kink_candidates`] looks for sign
/// changes of the landing-slip condition before refining each one.
const LANDING_GRID: u32 = 64;

/// Candidate kinks of `⟨s⟩(d)` in closed form: band offsets `d` at which a
/// spring's arc structure changes (forward convention, `V ≥ 0`). With the
/// stick `s = k + Vθ + X(θ)`, `X = b cos(θ + φ)`, `h⁺ = s − w` increases on
/// `θ + ψ ∈ [π − α, 2π + α]` and `h⁻ = s + w` decreases on
/// `θ + ψ' ∈ [α', π − α']` (`c sin ψ = b sin φ`, `c cos ψ = a + b cos φ`,
/// `α = asin(V/c)`; primes with `b cos φ − a`); a forward slip ends at the end
/// `θ_e` of an increasing piece, a backward slip at the end `θ_b` of a
/// decreasing one. These phases do not depend on `d`, so
///
/// * **window edges** (intermittent springs, `|d| < a`): a piece boundary
///   `β` crosses the landing or the lift-off where `d = a cos β` (e.g. a
///   forward slip that reaches the lift-off instead of ending before it);
/// * **landing slips**: at landing `s = 0 = w` and the band opens at
///   `a sin θ_c` while the stick moves at `V − b sin(θ_c + φ)`; the spring
///   slips from the landing iff `|V − b sin(θ_c + φ)| > a sin θ_c` — the sign
///   changes of `a sin θ − |V − b sin(θ + φ)|` over [`LANDING_GRID`] points,
///   bisected to rounding, give `d = a cos θ_c`;
/// * **grazes** (permanent springs): the stick that leaves a forward slip at
///   `θ_e` (`k = w(θ_e) − Vθ_e − X(θ_e)`) touches the lower band at the next
///   minimum `θ_m` of `h⁻` (the end of its decreasing piece) where
///   `h⁻(θ_m) = 2d − a cos θ_e − a cos θ_m + V(θ_m − θ_e) + X(θ_m) − X(θ_e)`
///   vanishes — linear in `d`; likewise the stick that leaves a backward slip
///   at `θ_b` grazes the upper band at the next end `θ_e` of an increasing
///   piece where `2d = a cos θ_b + a cos θ_e + V(θ_e − θ_b) + X(θ_e) − X(θ_b)`.
///
/// Trigonometry only, no spring solved. A candidate is only a candidate:
/// [`kinks`] checks it against the signatures of the springs either side
/// before using it.
pub(super) fn kink_candidates<T: Float, M: Math<T>>(d: &Drive<T>, v: T, mut found: impl FnMut(T)) {
    let a = d.a;
    let swing = |th: T| {
        let (s, c) = M::sin_cos(th);
        d.bc * c - d.bs * s
    };
    // Piece boundaries (phases in [0, 2π)): ends of the increasing pieces of
    // h⁺ and of the decreasing pieces of h⁻, and their starts.
    let c_up = M::hypot(a + d.bc, d.bs);
    let c_down = M::hypot(d.bc - a, d.bs);
    let up = (v < c_up).then(|| {
        let psi = M::atan2(d.bs, a + d.bc);
        let alpha = M::asin(v / c_up);
        (
            exact::period::wrap_tau(T::PI - alpha - psi),
            exact::period::wrap_tau(T::TAU + alpha - psi),
        )
    });
    let down = (v < c_down).then(|| {
        let psi = M::atan2(d.bs, d.bc - a);
        let alpha = M::asin(v / c_down);
        (
            exact::period::wrap_tau(alpha - psi),
            exact::period::wrap_tau(T::PI - alpha - psi),
        )
    });
    // Window edges.
    for beta in [
        up.map(|u| u.0),
        up.map(|u| u.1),
        down.map(|u| u.0),
        down.map(|u| u.1),
    ]
    .into_iter()
    .flatten()
    {
        found(a * M::sin_cos(beta).1);
    }
    // Grazes: the next θ after `from` congruent to `to` (mod 2π).
    let next = |from: T, to: T| {
        let mut x = to;
        while x <= from {
            x += T::TAU;
        }
        x
    };
    if let (Some((_, te)), Some((_, tb))) = (up, down) {
        let cos = |x: T| M::sin_cos(x).1;
        let tm = next(te, tb);
        found((a * cos(te) + a * cos(tm) - v * (tm - te) - swing(tm) + swing(te)) * T::HALF);
        let tn = next(tb, te);
        found((a * cos(tb) + a * cos(tn) + v * (tn - tb) + swing(tn) - swing(tb)) * T::HALF);
    }
    // The rest are zeros of functions of the landing phase θ_c ∈ [0, π]
    // (d = a cos θ_c, lift-off θ_l = 2π − θ_c), found on one trig grid.
    // With X(θ_l) = b cos θ_c cos φ + b sin θ_c sin φ:
    let swing_at_lift_off = |s: T, c: T| d.bc * c + d.bs * s;
    let swing_at_landing = |s: T, c: T| d.bc * c - d.bs * s;
    let mut grid = [(T::ZERO, T::ZERO, T::ONE); LANDING_GRID as usize + 1];
    for (i, g) in grid.iter_mut().enumerate() {
        let th = T::PI * T::from_u32(i as u32) / T::from_u32(LANDING_GRID);
        let (s, c) = M::sin_cos(th);
        *g = (th, s, c);
    }
    // Landing slips.
    let landing = |_: T, s: T, c: T| Some(a * s - (v - (d.bs * c + d.bc * s)).abs());
    offsets_of_zeros::<T, M>(a, &grid, landing, &mut found);
    // Pinches: the last stick reaches the lift-off with s = 0 (both bands
    // close there), from the landing or from the end of a slip inside the
    // window.
    let from_landing = |th: T, s: T, c: T| {
        Some(v * (T::TAU - th - th) + swing_at_lift_off(s, c) - swing_at_landing(s, c))
    };
    offsets_of_zeros::<T, M>(a, &grid, from_landing, &mut found);
    let inside = |th: T, x: T| x > th && x < T::TAU - th;
    for (end, sign) in [(up.map(|u| u.1), T::ONE), (down.map(|u| u.1), -T::ONE)] {
        let Some(te) = end else { continue };
        let (se, ce) = M::sin_cos(te);
        let (w_end, x_end) = (-(a * ce), d.bc * ce - d.bs * se);
        let after_slip = |th: T, s: T, c: T| {
            inside(th, te).then(|| {
                sign * (a * c + w_end) + v * (T::TAU - th - te) + swing_at_lift_off(s, c) - x_end
            })
        };
        offsets_of_zeros::<T, M>(a, &grid, after_slip, &mut found);
    }
}

/// The band offsets `d = a cos θ_c` at the sign changes of `h(θ_c, sin θ_c,
/// cos θ_c)` over `θ_c ∈ [0, π]`: on the `grid` (`(θ, sin θ, cos θ)`), each
/// change refined by [`illinois`] to 10⁻¹³ rad; `h` is `None`
/// where it does not apply (no change is sought across such a point).
fn offsets_of_zeros<T: Float, M: Math<T>>(
    a: T,
    grid: &[(T, T, T)],
    h: impl Fn(T, T, T) -> Option<T>,
    found: &mut impl FnMut(T),
) {
    let mut prev = grid
        .first()
        .and_then(|&(t, s, c)| h(t, s, c).map(|f| (t, f)));
    for &(t1, s1, c1) in grid.iter().skip(1) {
        let next = h(t1, s1, c1).map(|f| (t1, f));
        if let (Some((t0, f0)), Some((_, f1))) = (prev, next) {
            if (f0 < T::ZERO) != (f1 < T::ZERO) {
                let probe = |x: T| {
                    let (s, c) = M::sin_cos(x);
                    Ok::<_, ()>(match h(x, s, c) {
                        Some(v) => Probe::Value(v),
                        None => Probe::Stop,
                    })
                };
                if let Ok((lo, hi)) = illinois(
                    (t0, t1, f0, f1),
                    |_, _| T::from_f64(1e-13),
                    ZERO_ITERATIONS,
                    probe,
                ) {
                    found(a * M::sin_cos((lo + hi) * T::HALF).1);
                }
            }
        }
        prev = next;
    }
}

/// Most evaluations [`offsets_of_zeros`] spends refining one zero.
const ZERO_ITERATIONS: u32 = 40;

/// The kinks of the springs' `⟨s⟩` inside `[l, r]` (ξ), in increasing order,
/// searched in `t` of the segment's map `ξ = l + (r − l)(1 − cos t)/2`: the arc
/// structure ([`spring::signature`]) is sampled at [`KINK_SAMPLES`] interior
/// points equally spaced in `t`, and each change between neighbours is
/// located to [`KINK_RESOLUTION`]`·π` in `t`: by the closed-form candidate
/// inside the bracket if the signatures half that width either side of it
/// match the bracket's ends (two solves), else by bisection. Changes that
/// cancel between two samples are left to the adaptive quadrature. Returns
/// the number of springs solved.
pub(super) fn kinks<T: Float, M: Math<T>>(
    d: &Drive<T>,
    v: T,
    seg: &Search<'_, T>,
    offset: &impl Fn(T) -> T,
    mut found: impl FnMut(T),
) -> u32 {
    let (l, r, ends) = (seg.l, seg.r, seg.ends);
    let half = (r - l) * T::HALF;
    let calls = core::cell::Cell::new(0u32);
    let sig = |t: T| {
        calls.set(calls.get() + 1);
        let (_, cos_t) = M::sin_cos(t);
        spring::signature::<T, M>(seg.shape, d, offset(l + half * (T::ONE - cos_t)), v)
    };
    // ξ → t of the segment's map.
    let t_of = |xi: T| {
        let c = (T::ONE - (xi - l) / half).max(-T::ONE).min(T::ONE);
        M::atan2(M::sqrt((T::ONE - c) * (T::ONE + c)), c)
    };
    let step = T::PI / T::from_u32(KINK_SAMPLES + 1);
    let end = T::from_f64(KINK_END) * T::PI;
    let resolution = T::from_f64(KINK_RESOLUTION) * T::PI;
    let sample = |i: u32| match i {
        0 if ends.1 => end,
        i if i == KINK_SAMPLES + 1 && ends.0 => T::PI - end,
        i => step * T::from_u32(i.clamp(1, KINK_SAMPLES)),
    };
    let first = if ends.1 { 0 } else { 1 };
    let last = if ends.0 {
        KINK_SAMPLES + 1
    } else {
        KINK_SAMPLES
    };
    let mut t_prev = sample(first);
    let mut s_prev = sig(t_prev);
    for i in first + 1..=last {
        let t = sample(i);
        let s = sig(t);
        if s != s_prev && s.is_some() && s_prev.is_some() {
            // A closed-form candidate inside the bracket, confirmed by the
            // signatures half the resolution either side (or, on a side
            // where sliver arcs below the signatures' floor show a
            // transient code, [`KINK_CONFIRM_FAR`] and its square times
            // further, inside the bracket).
            let side = |tk: T, dir: T, want: Option<u32>| {
                let mut delta = resolution * T::HALF;
                for _ in 0..KINK_CONFIRM_LOOKS {
                    let at = tk + dir * delta;
                    if (at - t_prev) * (t - at) <= T::ZERO {
                        return false;
                    }
                    if sig(at) == want {
                        return true;
                    }
                    delta *= T::from_f64(KINK_CONFIRM_FAR);
                }
                false
            };
            let confirmed = seg
                .hint
                .iter()
                .map(|&xi| t_of(xi))
                .filter(|&tk| tk - resolution * T::HALF > t_prev && tk + resolution * T::HALF < t)
                .take(2)
                .find(|&tk| side(tk, -T::ONE, s_prev) && side(tk, T::ONE, s));
            // The confirmed candidate, else the bisection of the bracket
            // down to the resolution; either in ξ through the segment's map.
            let tk = confirmed.unwrap_or_else(|| {
                let (mut lo, mut hi) = (t_prev, t);
                while hi - lo > resolution {
                    let mid = (lo + hi) * T::HALF;
                    if sig(mid) == s_prev {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                (lo + hi) * T::HALF
            });
            let (_, cos_t) = M::sin_cos(tk);
            found(l + half * (T::ONE - cos_t));
        }
        t_prev = t;
        s_prev = s;
    }
    calls.get()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::float::Libm;

    /// The closed-form candidates cover the changes of the springs' arc
    /// structure: over 60 random drives (a ∈ [0.05, 2.95], b ∈ [0.1, 5], any
    /// φ, V ∈ [0, c], a fifth at V = 0), the signature is scanned at 6000
    /// offsets across `d ∈ (−a, 1]`; each change away from the onset `d = a`
    /// (a segment end, not a kink) and the rim must have a candidate within
    /// 3·10⁻³ in `d` (the sliver layer of [`KINK_CONFIRM_FAR`] moves the
    /// scan's change that far from the kink). Changes without one fall back
    /// to the bisection; they are counted and bounded: at most 3 % (seen:
    /// 6 of 437 over 200 drives at 20 000 offsets, the last slip of a
    /// window vanishing at negative `d` with a > 1).
    #[test]
    fn kink_candidates_cover_the_arc_structure_changes() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut total, mut covered) = (0u32, 0u32);
        for _ in 0..60 {
            let a = 0.05 + 2.9 * rnd();
            let b = 10f64.powf(-1.0 + 1.7 * rnd());
            let phi = core::f64::consts::PI * (2.0 * rnd() - 1.0);
            let d = Drive::new::<Libm>(a, b, phi);
            let v = if rnd() < 0.2 {
                0.0
            } else {
                d.c_forward::<Libm>() * rnd()
            };
            let shape = Shape::of::<Libm>(&d, v);
            let mut cands: heapless::Vec<f64, MAX_CANDIDATES> = heapless::Vec::new();
            kink_candidates::<f64, Libm>(&d, v, |x| {
                let _ = cands.push(x);
            });
            let n = 6000;
            let (mut prev, mut prev_d) = (None, 1.0);
            for i in 0..=n {
                let dd = 1.0 - (1.0 + a) * (f64::from(i) / f64::from(n));
                let sg = spring::signature::<f64, Libm>(&shape, &d, dd, v);
                let interior = !(dd <= a && prev_d >= a) && dd > -a + 1e-3;
                if i > 0 && sg != prev && sg.is_some() && prev.is_some() && interior {
                    total += 1;
                    if cands.iter().any(|&c| c <= prev_d + 3e-3 && c >= dd - 3e-3) {
                        covered += 1;
                    }
                }
                prev = sg;
                prev_d = dd;
            }
        }
        std::println!("kink candidates: {covered} of {total} changes covered");
        assert!(total >= 60, "{total}");
        assert!(
            f64::from(total - covered) <= 0.03 * f64::from(total),
            "{covered} of {total}"
        );
    }

    /// Each closed-form landing-slip threshold is a change of the spring's
    /// arc structure as the event walk sees it: the signatures a little
    /// either side differ (δ = 10⁻⁴ a in `d`, far above the walk's 10⁻⁶ rad
    /// arc floor, far below the distance to the next threshold).
    #[test]
    fn landing_thresholds_are_arc_structure_changes() {
        let mut checked = 0;
        for &(a, b, phi, v) in &[
            (0.5, 1.0, 0.3, 0.2),
            (0.9, 1.0, 0.3, 0.2),
            (1.5, 0.7, 2.0, 0.1),
            (0.25, 1.0, 0.3, 0.0),
            (2.0, 0.4, -1.0, 0.05),
        ] {
            let d = Drive::new::<Libm>(a, b, phi);
            let mut found: heapless::Vec<f64, MAX_CANDIDATES> = heapless::Vec::new();
            let mut grid = [(0.0, 0.0, 1.0); LANDING_GRID as usize + 1];
            for (i, g) in grid.iter_mut().enumerate() {
                let th = core::f64::consts::PI * i as f64 / f64::from(LANDING_GRID);
                *g = (th, th.sin(), th.cos());
            }
            let landing = |_: f64, s: f64, c: f64| Some(a * s - (v - (d.bs * c + d.bc * s)).abs());
            offsets_of_zeros::<f64, Libm>(a, &grid, landing, &mut |x| {
                let _ = found.push(x);
            });
            for &dk in &found {
                assert!(dk.abs() < a);
                let delta = 1e-4 * a;
                if found
                    .iter()
                    .any(|&o| o != dk && (o - dk).abs() < 4.0 * delta)
                {
                    continue;
                }
                let shape = Shape::of::<Libm>(&d, v);
                let lo = spring::signature::<f64, Libm>(&shape, &d, dk - delta, v);
                let hi = spring::signature::<f64, Libm>(&shape, &d, dk + delta, v);
                assert!(lo.is_some() && hi.is_some());
                assert_ne!(lo, hi, "a={a} b={b} phi={phi} v={v} d={dk}");
                checked += 1;
            }
        }
        assert!(checked >= 3, "{checked}");
    }

    /// The pinches (the last stick of a window reaching the lift-off with
    /// `s = 0`, from the landing or from a slip inside the window: the last
    /// two zero sets of [`kink_candidates`]) are candidates where the event
    /// walk's arc structure changes. Nine drives whose intermittent springs
    /// have such a kink (found by a scan over 300 random drives, 23 kinks, of
    /// which one had no candidate near it: the 1 in 132 of the module docs),
    /// with landing phases `θ_c` from 0.26 to 2.8 rad: the signatures are
    /// scanned at 4000 offsets across `d ∈ (−a, min(a, 1))`; at each change
    /// where only the window's last slip turns from forward to backward (or
    /// back) — the stick before it meets the lift-off point, where both bands
    /// close — a candidate must lie in the layer between the two codes'
    /// regions, each edge bisected on the signatures to 10⁻¹³; and each drive
    /// must show such a change. Why there: the walk's arcs, not the
    /// candidates, are the reference; the signatures drop arcs shorter than
    /// 10⁻⁶ rad (`liftoff::SIGNATURE_MIN_ARC`), so next to the kink neither
    /// slip shows, and the kink, where both have zero length, lies inside that
    /// layer (seen 10⁻⁷ to 2·10⁻⁵ wide: how fast the slips grow depends on the
    /// slope of the pinch condition, so the width has no simple closed form).
    /// Slack 10⁻¹⁰ in `d` either side: the candidate's own refinement is
    /// 10⁻¹³ rad in `θ_c` (`d = a cos θ_c`, so ≤ 3·10⁻¹³ in `d`), the
    /// bisection 10⁻¹³.
    #[test]
    fn pinches_are_candidates_at_the_walks_arc_changes() {
        // (a, b, φ, V): four pinches after a slip with θ_c past π/2, three
        // before it, two from the landing.
        let drives = [
            (
                1.386_145_305_242_113_5,
                1.614_770_542_262_740_7,
                3.689_116_834_826_463,
                0.807_266_038_718_036_8,
            ),
            (
                1.631_094_769_531_622,
                4.872_139_072_817_446,
                3.831_386_212_246_653,
                3.537_917_644_013_905_5,
            ),
            (
                0.424_805_949_951_917_9,
                2.265_335_014_931_619,
                -2.445_517_808_501_305_6,
                1.883_667_622_557_258,
            ),
            (
                0.563_269_817_182_083_1,
                1.496_667_431_434_648_9,
                -2.508_573_746_417_526,
                1.056_954_884_947_099_3,
            ),
            (
                0.928_452_126_681_349_6,
                1.102_442_084_699_159_8,
                2.939_390_167_425_133_6,
                0.264_440_026_563_076_8,
            ),
            (
                0.619_673_262_562_157_5,
                3.141_914_393_694_939,
                3.034_509_724_916_193,
                2.483_042_334_817_35,
            ),
            (
                1.916_341_174_664_837_3,
                1.555_209_285_862_763_7,
                -2.478_885_007_907_387_6,
                0.396_277_125_265_595_9,
            ),
            (
                0.825_988_086_178_038,
                0.184_524_092_239_235_8,
                -2.679_140_962_990_061,
                0.066_698_578_475_972_2,
            ),
            (
                1.343_509_026_520_937,
                0.817_465_407_964_331_9,
                -2.706_539_191_461_682,
                0.337_271_303_231_719_67,
            ),
        ];
        for &(a, b, phi, v) in &drives {
            let d = Drive::new::<Libm>(a, b, phi);
            let shape = Shape::of::<Libm>(&d, v);
            let mut cands: heapless::Vec<f64, MAX_CANDIDATES> = heapless::Vec::new();
            kink_candidates::<f64, Libm>(&d, v, |x| {
                let _ = cands.push(x);
            });
            let sig = |x: f64| spring::signature::<f64, Libm>(&shape, &d, x, v);
            // The edge of `code`'s region between `inside` (that code) and `outside`.
            let edge = |code: Option<u32>, mut inside: f64, mut outside: f64| {
                while (inside - outside).abs() > 1e-13 {
                    let m = 0.5 * (inside + outside);
                    if sig(m) == code {
                        inside = m;
                    } else {
                        outside = m;
                    }
                }
                inside
            };
            let top = a.min(1.0) - 1e-9;
            let span = top + a - 1e-9;
            let n = 4000;
            let mut pinches = 0;
            let (mut prev, mut prev_d) = (sig(top), top);
            for i in 1..=n {
                let dd = top - span * (f64::from(i) / f64::from(n));
                let s = sig(dd);
                if let (Some(p), Some(q)) = (prev, s) {
                    let last = (p % 4, q % 4);
                    if p / 4 == q / 4 && p / 4 > 0 && (last == (2, 3) || last == (3, 2)) {
                        let hi = edge(prev, prev_d, dd) + 1e-10;
                        let lo = edge(s, dd, prev_d) - 1e-10;
                        assert!(
                            cands.iter().any(|&c| c >= lo && c <= hi),
                            "a={a} b={b} φ={phi} V={v}: arcs {p} -> {q} in d ∈ [{lo}, {hi}], no candidate: {cands:?}"
                        );
                        pinches += 1;
                    }
                }
                prev = s;
                prev_d = dd;
            }
            assert!(pinches > 0, "a={a} b={b} φ={phi} V={v}: no pinch seen");
        }
    }
}
