// newton-tr: a projected truncated Newton method in a trust region, on the problem's exact
// Hessian products (Problem::hessianProduct), for a box-constrained problem.
//
// Why: the unbiased objective through T's Gram (objective/TransportLoss.h) has its Hessian
// product at the price of one evaluation (one product with the 1250² P), and its loss,
// sqrt(S/EᵀPE) + λ·mean(E²), is far from quadratic: L-BFGS needs 100–300 evaluations on the
// bundled part, where Newton's steps need some 30–60 products in all (docs/RESEARCH.md,
// issue 32's thirteenth pass).
//
// One iteration, at x with gradient g (Bertsekas' projected Newton, with Steihaug's CG):
//   1. The active set A: the variables at (within ε of) a bound whose gradient points out of
//      the box, ε = min(10⁻³·(upper − lower), ‖x − P(x − g)‖₂); the others are free (F).
//   2. Steihaug–Toint CG on the free variables' Newton system H_FF·d = −g_F from d = 0, each
//      step one Hessian product, until the residual is below min(0.5, sqrt‖g_F‖)·‖g_F‖
//      (the forcing term), the step reaches the trust radius Δ, or a direction of non-positive
//      curvature appears (then the step goes along it to the radius: the loss is not convex).
//      The active variables' step goes to their bound.
//   3. A backtracking search on the projected arc x(α) = P(x + α·d), α = 1, ½, ¼, ...,
//      accepting the first point with f(x) − f(x(α)) ≥ σ·(−g_Fᵀ(x(α) − x)_F + g_Aᵀ(x − x(α))_A),
//      σ = 10⁻⁴; each trial evaluates f and ∇f, so the accepted point has its gradient.
//   4. Δ doubles after a full step (α = 1) that the radius or negative curvature stopped, and
//      becomes α·‖d_F‖ after a shortened one. Δ starts at 0.1·(upper − lower) (tuned on the
//      bundled part at λ 3–100 from two starts; docs/RESEARCH.md).
// It stops when the projected gradient ‖x − P(x − g)‖∞ ≤ 10⁻⁸·max(1, |f|) ("converged"), when a
// step's decrease is at most relativeFunctionTolerance·|f| (when set), when a step changes f by
// less than 10⁻¹⁵·|f| ("converged to roundoff"), when no α ≥ 2⁻⁴⁰ decreases f (roundoff as
// well, or a failure before any progress: a Hessian or gradient that does not fit the loss),
// or at `iterations` steps. Deterministic: the same problem and start give the same iterates.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "optimize/OptimizerDetail.h"

namespace sl::detail {

namespace {

constexpr double kInitialRadius = 0.1;          // × (upper − lower)
constexpr double kProjectedGradientTol = 1e-8;  // × max(1, |f|)
constexpr double kArmijo = 1e-4;
constexpr int kMaxHalvings = 40;
constexpr double kRoundoff = 1e-15;

double dotOf(const std::vector<double>& a, const std::vector<double>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
    return s;
}

}  // namespace

void minimizeNewtonTr(Run& run, std::vector<double>& x) {
    const OptimizerOptions& o = run.options();
    const Problem& problem = run.problem();
    const double lo = problem.lower, hi = problem.upper;
    const size_t n = x.size();
    const int maxCg = static_cast<int>(std::min<size_t>(n, 100));
    run.summary.settings = "trust radius from " + formatNumber(kInitialRadius * (hi - lo)) +
                           ", Steihaug CG (at most " + std::to_string(maxCg) +
                           " Hessian products a step), projected arc search";
    if (o.relativeFunctionTolerance > 0)
        run.summary.settings += "; ftol_rel " + formatNumber(o.relativeFunctionTolerance);

    std::vector<double> g(n), gn(n), xn(n), d(n), r(n), p(n), hp(n), z(n);
    std::vector<char> active(n);
    auto hessian = [&](const std::vector<double>& v, std::vector<double>& out) {
        problem.hessianProduct(x, v, out);
        ++run.summary.hessianProducts;
        for (size_t i = 0; i < n; ++i) {
            if (!std::isfinite(out[i]))
                throw NonFinite(
                    "minimize (method 'newton-tr'): the Hessian product is not finite "
                    "(Hv[" +
                    std::to_string(i) + "] = " + formatNumber(out[i]) + ") at iteration " +
                    std::to_string(run.lastIteration() + 1) +
                    "; stopping (no NaN leaves the optimizer)");
            if (active[i]) out[i] = 0;  // H_FF·v: only the free rows
        }
    };

    double f = run.evaluate(x, g, false);
    if (!run.record(f, x)) {
        run.summary.termination = "stopped by callback";
        return;
    }
    double radius = kInitialRadius * (hi - lo);
    for (int it = 1; it <= o.iterations; ++it) {
        // 1. Converged? The active set.
        double pgInf = 0, pg2 = 0;
        for (size_t i = 0; i < n; ++i) {
            const double step = x[i] - clampTo(x[i] - g[i], lo, hi);
            pgInf = std::max(pgInf, std::abs(step));
            pg2 += step * step;
        }
        if (pgInf <= kProjectedGradientTol * std::max(1.0, std::abs(f))) {
            run.summary.termination = "converged: projected gradient " + formatNumber(pgInf);
            return;
        }
        const double eps = std::min(1e-3 * (hi - lo), std::sqrt(pg2));
        for (size_t i = 0; i < n; ++i)
            active[i] = (x[i] <= lo + eps && g[i] > 0) || (x[i] >= hi - eps && g[i] < 0);

        // 2. Steihaug–Toint CG on the free variables, z the step.
        for (size_t i = 0; i < n; ++i) {
            r[i] = active[i] ? 0.0 : -g[i];
            p[i] = r[i];
            z[i] = 0;
        }
        double rr = dotOf(r, r);
        const double r0 = std::sqrt(rr), forcing = std::min(0.5, std::sqrt(r0)) * r0;
        bool reachedRadius = false;
        auto toRadius = [&] {  // z += τ·p, τ ≥ 0 with ‖z + τ·p‖ = radius
            const double a = dotOf(p, p), b = 2 * dotOf(z, p), c = dotOf(z, z) - radius * radius;
            const double tau = (-b + std::sqrt(std::max(0.0, b * b - 4 * a * c))) / (2 * a);
            for (size_t i = 0; i < n; ++i) z[i] += tau * p[i];
            reachedRadius = true;
        };
        for (int k = 0; k < maxCg && r0 > 0; ++k) {
            hessian(p, hp);
            const double pHp = dotOf(p, hp);
            if (pHp <= 0) {
                toRadius();
                break;
            }
            const double a = rr / pHp;
            double zz = 0;
            for (size_t i = 0; i < n; ++i) zz += (z[i] + a * p[i]) * (z[i] + a * p[i]);
            if (std::sqrt(zz) >= radius) {
                toRadius();
                break;
            }
            for (size_t i = 0; i < n; ++i) {
                z[i] += a * p[i];
                r[i] -= a * hp[i];
            }
            const double rrNext = dotOf(r, r);
            if (std::sqrt(rrNext) <= forcing) break;
            const double beta = rrNext / rr;
            for (size_t i = 0; i < n; ++i) p[i] = r[i] + beta * p[i];
            rr = rrNext;
        }
        double freeStep = 0;
        for (size_t i = 0; i < n; ++i) {
            d[i] = active[i] ? (g[i] > 0 ? lo : hi) - x[i] : z[i];
            if (!active[i]) freeStep += z[i] * z[i];
        }
        freeStep = std::sqrt(freeStep);

        // 3. The projected arc search.
        double alpha = 1, fn = f;
        bool accepted = false;
        for (int h = 0; h <= kMaxHalvings; ++h, alpha *= 0.5) {
            double predicted = 0;
            for (size_t i = 0; i < n; ++i) {
                xn[i] = clampTo(x[i] + alpha * d[i], lo, hi);
                predicted += active[i] ? g[i] * (x[i] - xn[i]) : -g[i] * (xn[i] - x[i]);
            }
            fn = run.evaluate(xn, gn, false);
            if (f - fn >= kArmijo * predicted && fn <= f) {
                accepted = true;
                break;
            }
        }
        if (!accepted) {
            run.summary.termination = run.progressed()
                                          ? "converged to roundoff (no decrease along the step)"
                                          : "no decrease along the first step";
            run.summary.failed = !run.progressed();
            return;
        }

        // 4. The trust radius.
        if (alpha == 1 && reachedRadius)
            radius *= 2;
        else if (alpha < 1)
            radius = std::max(alpha * freeStep, 1e-12 * (hi - lo));

        const double decrease = f - fn;
        x.swap(xn);
        g.swap(gn);
        f = fn;
        if (!run.record(f, x)) {
            run.summary.termination = "stopped by callback";
            return;
        }
        if (o.relativeFunctionTolerance > 0 &&
            decrease <= o.relativeFunctionTolerance * std::abs(f)) {
            run.summary.termination = "converged: relative decrease " +
                                      formatNumber(decrease / std::abs(f)) + " <= ftol_rel";
            return;
        }
        if (decrease <= kRoundoff * std::abs(f)) {
            run.summary.termination = "converged to roundoff";
            return;
        }
    }
    run.summary.termination = "iteration limit reached (" + std::to_string(o.iterations) + ")";
}

}  // namespace sl::detail
