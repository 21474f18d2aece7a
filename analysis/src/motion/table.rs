//! The steady-state law μ(V)/μ₀ tabulated once per run, with a stated
//! interpolation error, so that a long integration never calls the exact
//! solver per step.
//!
//! Nodes lie on `[−c', c]` (`c`, `c'` the forward and backward critical
//! velocities in units of ωW₀, eq. 8); outside it the law is `±1` exactly
//! (continuous sliding). `V = 0` carries two values, `μ(0⁺)` and `μ(0⁻)`
//! (the static band; with lift-off both are the unique μ(0)). Every value
//! comes from [`Law`] (one μ(v) for every contact model). Between nodes the
//! law is interpolated linearly.
//!
//! **Refinement and error estimate.** Each side starts from 64 uniform cells
//! and a cell is halved while the exact value at its midpoint differs from the
//! chord by more than `tol` (the midpoint then becomes a node). On a cell
//! where the law is convex or concave (every cell but those holding an
//! inflection point, which refinement makes short) the chord's error `e` is
//! concave (or convex) with `e = 0` at both ends, so it lies above the line
//! from an end to its extremum: at the midpoint it is at least half its
//! largest value. A slope jump (the kinks at `V = 0⁺` and at `c`) is the
//! extreme case, where the factor 2 is attained. So twice the largest
//! midpoint deviation of the accepted cells bounds the interpolation error.
//! The nodes' own errors (the solver's stated bound `β`, e.g. the exact
//! solver's 1e-9·(1 + b) μ₀) enter twice: each measured deviation may be off
//! by `2β` (midpoint and chord), and the interpolated values by `β`. The
//! reported [`MuTable::interpolation_error`] is `2·max dev + 5β`. Cells are
//! not split below `1e-9·c` (the kinks are then resolved to that width;
//! their deviation still counts).

use super::law::{Law, LawError};

/// Cells per side before refinement.
const START_CELLS: usize = 64;
/// Smallest cell, relative to the side's critical velocity.
const MIN_CELL: f64 = 1e-9;
/// Most nodes per side (a law needing more is reported, not truncated).
pub const MAX_NODES: usize = 200_000;

/// Why a table could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum TableError {
    /// The contact's solver failed.
    Law(LawError),
    /// The tolerance needs more than [`MAX_NODES`] nodes per side.
    TooManyNodes,
    /// The tabulated law decreases somewhere by more than the solver's error:
    /// its inverse (the massless body) is not unique.
    NotMonotone {
        /// Where, in units of ωW₀.
        at: f64,
    },
}

impl std::fmt::Display for TableError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TableError::Law(e) => write!(f, "tabulating {e}"),
            TableError::TooManyNodes => write!(
                f,
                "mu(v) needs more than {MAX_NODES} table nodes per side for this --tol"
            ),
            TableError::NotMonotone { at } => write!(
                f,
                "mu(v) decreases near v/(omega W0) = {at:.6}: the massless body's velocity is not unique"
            ),
        }
    }
}

impl std::error::Error for TableError {}

/// One side of the law: nodes `0 = v₀ < v₁ < … < v_n = c` (of |V|) and values.
#[derive(Debug, Clone)]
struct Side {
    v: Vec<f64>,
    mu: Vec<f64>,
}

impl Side {
    /// Builds the side with law `f(|V|)` on `(0, c]` and value `at0` at 0.
    fn build(
        c: f64,
        at0: f64,
        tol: f64,
        f: &impl Fn(f64) -> Result<f64, LawError>,
    ) -> Result<(Side, f64), TableError> {
        if c <= 0.0 {
            return Ok((
                Side {
                    v: vec![0.0],
                    mu: vec![at0],
                },
                0.0,
            ));
        }
        let mut v = Vec::with_capacity(4 * START_CELLS);
        let mut mu = Vec::with_capacity(4 * START_CELLS);
        v.push(0.0);
        mu.push(at0);
        let mut worst = 0.0f64;
        let min_cell = MIN_CELL * c;
        // Depth-first refinement of each starting cell, emitting nodes in order.
        for i in 0..START_CELLS {
            let lo = c * i as f64 / START_CELLS as f64;
            let hi = c * (i + 1) as f64 / START_CELLS as f64;
            let f_lo = *mu.last().unwrap_or(&at0);
            let f_hi = if i + 1 == START_CELLS {
                1.0
            } else {
                f(hi).map_err(TableError::Law)?
            };
            let mut stack = vec![(hi, f_hi)];
            let (mut a, mut fa) = (lo, f_lo);
            while let Some(&(b, fb)) = stack.last() {
                let m = 0.5 * (a + b);
                let fm = f(m).map_err(TableError::Law)?;
                let dev = (fm - 0.5 * (fa + fb)).abs();
                if dev > tol && b - a > 2.0 * min_cell {
                    stack.push((m, fm));
                    continue;
                }
                worst = worst.max(dev);
                stack.pop();
                v.push(b);
                mu.push(fb);
                if v.len() > MAX_NODES {
                    return Err(TableError::TooManyNodes);
                }
                a = b;
                fa = fb;
            }
        }
        Ok((Side { v, mu }, worst))
    }

    /// Linear interpolation at `x ≥ 0` (`1` beyond the last node).
    fn eval(&self, x: f64) -> f64 {
        let n = self.v.len();
        if x >= self.v[n - 1] {
            return 1.0;
        }
        let i = self.v.partition_point(|&t| t <= x).max(1);
        let (x0, x1) = (self.v[i - 1], self.v[i]);
        let t = (x - x0) / (x1 - x0);
        self.mu[i - 1] + t * (self.mu[i] - self.mu[i - 1])
    }

    /// The smallest `x ≥ 0` with `eval(x) = y`, for `mu[0] ≤ y ≤ 1`
    /// (the values are non-decreasing, checked at build).
    fn inverse(&self, y: f64) -> f64 {
        let n = self.v.len();
        if n == 1 || y <= self.mu[0] {
            return 0.0;
        }
        if y >= 1.0 {
            return self.v[n - 1];
        }
        let i = self.mu.partition_point(|&m| m < y).clamp(1, n - 1);
        let (m0, m1) = (self.mu[i - 1], self.mu[i]);
        let (x0, x1) = (self.v[i - 1], self.v[i]);
        if m1 <= m0 {
            return x0;
        }
        x0 + (y - m0) / (m1 - m0) * (x1 - x0)
    }

    /// The largest chord slope (units μ₀ per ωW₀).
    fn max_slope(&self) -> f64 {
        self.v
            .windows(2)
            .zip(self.mu.windows(2))
            .map(|(v, m)| (m[1] - m[0]) / (v[1] - v[0]))
            .fold(0.0, f64::max)
    }

    /// Makes the values non-decreasing, refusing a decrease beyond `slack`.
    fn monotone(&mut self, slack: f64, sign: f64) -> Result<(), TableError> {
        for i in 1..self.mu.len() {
            if self.mu[i] < self.mu[i - 1] {
                if self.mu[i - 1] - self.mu[i] > slack {
                    return Err(TableError::NotMonotone {
                        at: sign * self.v[i],
                    });
                }
                self.mu[i] = self.mu[i - 1];
            }
        }
        Ok(())
    }
}

/// μ(V)/μ₀ on both sides of `V = 0` (dimensionless, `V = v/(ωW₀)`).
#[derive(Debug, Clone)]
pub struct MuTable {
    fwd: Side,
    /// The backward side stored as the mirrored law: `μ(−x) = −bwd(x)`.
    bwd: Side,
    /// `μ(0⁺)/μ₀`, the upper end of the static band.
    pub mu_0plus: f64,
    /// `μ(0⁻)/μ₀`, the lower end of the static band.
    pub mu_0minus: f64,
    /// Largest interpolation error (twice the largest midpoint deviation,
    /// plus five times the solver's bound: module docs), μ₀.
    pub interpolation_error: f64,
    /// Forward critical velocity c (units ωW₀).
    pub c_forward: f64,
    /// Backward critical velocity c' (units ωW₀).
    pub c_backward: f64,
}

impl MuTable {
    /// Tabulates `law` to interpolation tolerance `tol` (units μ₀); the
    /// solver is asked for `tol` too.
    ///
    /// # Errors
    /// [`TableError`].
    pub fn new(law: &Law, tol: f64) -> Result<Self, TableError> {
        let zero = law.at(0.0, tol).map_err(TableError::Law)?;
        let (plus, minus) = (zero.upper, zero.lower);
        let (c, cb) = law.critical().map_err(TableError::Law)?;
        let solver = std::cell::Cell::new(zero.bound);
        let eval = |x: f64| {
            let (m, b) = law.mu(x, tol)?;
            solver.set(solver.get().max(b));
            Ok(m)
        };
        let (mut fwd, e1) = Side::build(c, plus, tol, &eval)?;
        // The backward side is stored mirrored: bwd(x) = −μ(−x), on (0, c'].
        let (mut bwd, e2) = Side::build(cb, -minus, tol, &|x| eval(-x).map(|m| -m))?;
        let solver = solver.get();
        fwd.monotone(2.0 * solver, 1.0)?;
        bwd.monotone(2.0 * solver, -1.0)?;
        Ok(MuTable {
            fwd,
            bwd,
            mu_0plus: plus,
            mu_0minus: minus,
            interpolation_error: 2.0 * e1.max(e2) + 5.0 * solver,
            c_forward: c,
            c_backward: cb,
        })
    }

    /// μ(V)/μ₀ for `V ≠ 0`; at `V = 0` the side is chosen by `dir` (+1: 0⁺).
    pub fn mu(&self, v: f64, dir: i8) -> f64 {
        if v > 0.0 || (v == 0.0 && dir > 0) {
            self.fwd.eval(v)
        } else {
            -self.bwd.eval(-v)
        }
    }

    /// The velocity at which the law equals `g` (the massless body):
    /// 0 inside the static band `[μ(0⁻), μ(0⁺)]`, else the smallest |V| on the
    /// side `g` lies on. `|g| ≥ 1` gives the critical velocity of that side.
    pub fn inverse(&self, g: f64) -> f64 {
        if g > self.mu_0plus {
            self.fwd.inverse(g)
        } else if g < self.mu_0minus {
            -self.bwd.inverse(-g)
        } else {
            0.0
        }
    }

    /// The largest slope dμ/dV of the table (μ₀ per ωW₀).
    pub fn max_slope(&self) -> f64 {
        self.fwd.max_slope().max(self.bwd.max_slope())
    }

    /// Number of nodes (both sides).
    pub fn nodes(&self) -> usize {
        self.fwd.v.len() + self.bwd.v.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::{exact, Groups, Libm};

    /// The table reproduces the exact solver at 2 000 off-node velocities to
    /// within its stated interpolation error (module docs) plus the exact
    /// solver's own bound at each velocity.
    #[test]
    fn table_within_its_error_estimate() {
        let g = Groups::from_ratio(0.5, 2.0, 0.7).unwrap();
        let d = model_core::Scene::dimensionless(g).unwrap().drive();
        let law = Law::of(&model_core::Scene::dimensionless(g).unwrap());
        let t = MuTable::new(&law, 1e-6).unwrap();
        let (c, cb) = (t.c_forward, t.c_backward);
        let mut worst = 0.0f64;
        for i in 1..2000 {
            let x = -cb * 1.1 + (c + cb) * 1.2 * (i as f64 + 0.37) / 2000.0;
            if x == 0.0 {
                continue;
            }
            let e = exact::mu_over_mu0::<f64, Libm>(&d, x).unwrap();
            worst = worst.max((t.mu(x, 1) - e).abs() - exact::error_bound::<f64, Libm>(&d));
        }
        assert!(
            worst <= t.interpolation_error,
            "worst {worst:e} vs estimate {:e}",
            t.interpolation_error
        );
        // The inverse undoes the law outside the band.
        for &y in &[t.mu_0plus + 0.1, 0.9, t.mu_0minus - 0.05] {
            let v = t.inverse(y);
            assert!((t.mu(v, 1) - y).abs() < 1e-12, "y = {y}");
        }
    }
}
