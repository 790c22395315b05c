// Tests for src/optimize: every method on a box-constrained quadratic, Adam's first steps by
// hand, MLSL against L-BFGS on a function with several minima, the callback protocol, option
// errors, NaN handling, and ceres-lbfgs on a 1250-texel problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "app/pipeline/InitialState.h"
#include "core/Color.h"
#include "core/Error.h"
#include "io/EnvMapIO.h"
#include "optimize/Optimizer.h"

using namespace sl;

namespace {

/// f(x) = Σ a_i (x_i − c_i)²; on [0, 1] the minimizer is clamp(c, 0, 1).
struct Quadratic {
    std::vector<double> a = {1.0, 2.0, 0.5, 4.0, 1.5, 3.0};
    std::vector<double> c = {-0.5, 0.3, 1.7, 0.8, 1.2, -0.1};  // four of six outside [0, 1]

    Problem problem() const {
        Problem p;
        p.dimension = a.size();
        p.evaluate = [a = a, c = c](std::span<const double> x, std::span<double> g) {
            double f = 0;
            for (size_t i = 0; i < x.size(); ++i) {
                f += a[i] * (x[i] - c[i]) * (x[i] - c[i]);
                if (!g.empty()) g[i] = 2 * a[i] * (x[i] - c[i]);
            }
            return f;
        };
        p.hessianProduct = [a = a](std::span<const double>, std::span<const double> v,
                                   std::span<double> hv) {
            for (size_t i = 0; i < v.size(); ++i) hv[i] = 2 * a[i] * v[i];
        };
        return p;
    }
    std::vector<double> solution() const {
        std::vector<double> s;
        for (double ci : c) s.push_back(std::clamp(ci, 0.0, 1.0));
        return s;
    }
    double minimum() const {
        double f = 0;
        auto s = solution();
        for (size_t i = 0; i < a.size(); ++i) f += a[i] * (s[i] - c[i]) * (s[i] - c[i]);
        return f;
    }
};

double maxAbsDiff(const std::vector<double>& u, const std::vector<double>& v) {
    double d = 0;
    for (size_t i = 0; i < u.size(); ++i) d = std::max(d, std::abs(u[i] - v[i]));
    return d;
}

double evalAt(const Problem& p, const std::vector<double>& x) {
    return p.evaluate(x, {});
}

/// 2-D, four Gaussian wells of different depth in a shallow bowl:
/// f = 0.2·|x − (0.5, 0.5)|² − Σ_k d_k exp(−|x − c_k|² / (2σ²)), σ = 0.08.
/// The deepest well is near (0.72, 0.78); a start at (0.12, 0.12) sits in the well at (0.2, 0.2).
Problem wells() {
    Problem p;
    p.dimension = 2;
    p.evaluate = [](std::span<const double> x, std::span<double> g) {
        static const double cx[4] = {0.2, 0.2, 0.75, 0.72}, cy[4] = {0.2, 0.75, 0.25, 0.78};
        static const double d[4] = {0.6, 0.8, 0.7, 1.0};
        const double s2 = 0.08 * 0.08;
        double f = 0.2 * ((x[0] - 0.5) * (x[0] - 0.5) + (x[1] - 0.5) * (x[1] - 0.5));
        double gx = 0.4 * (x[0] - 0.5), gy = 0.4 * (x[1] - 0.5);
        for (int k = 0; k < 4; ++k) {
            const double dx = x[0] - cx[k], dy = x[1] - cy[k];
            const double e = d[k] * std::exp(-(dx * dx + dy * dy) / (2 * s2));
            f -= e;
            gx += e * dx / s2;
            gy += e * dy / s2;
        }
        if (!g.empty()) {
            g[0] = gx;
            g[1] = gy;
        }
        return f;
    };
    return p;
}

struct Options : OptimizerOptions {
    explicit Options(const std::string& m, int iters = 100) {
        method = parseOptimizerMethod(m);
        iterations = iters;
    }
};

}  // namespace

TEST(Optimize, EveryMethodSolvesBoxConstrainedQuadratic) {
    const Quadratic q;
    const Problem p = q.problem();
    struct Case {
        std::string method;
        int iterations;
        double xTol;  // max |x − x*|
    };
    // Tolerances ~100× above what each method reaches here (measured: adam 500 steps at lr
    // 0.01 9e-13, lbfgs 8e-11, mma 1.3e-9, ccsaq 9e-10, mlsl 2e-12, ceres-lbfgs 1.3e-11).
    // Adam's step is normalized, so it needs a smaller lr than the paper's 0.02 (which stops at
    // 1.3e-3 after 100 steps) and more steps to settle on the interior minima.
    const std::vector<Case> cases = {{"adam", 500, 1e-10},    {"lbfgs", 200, 1e-8},
                                     {"mma", 300, 1e-7},      {"ccsaq", 300, 1e-7},
                                     {"mlsl", 2000, 1e-8},    {"ceres-lbfgs", 200, 1e-8},
                                     {"newton-tr", 50, 1e-10}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.method);
        Options o(c.method, c.iterations);
        o.learningRate = 0.01;
        std::vector<double> x(p.dimension, 0.5);
        const OptimizerSummary s = minimize(p, x, o);
        EXPECT_LT(maxAbsDiff(x, q.solution()), c.xTol) << s.briefReport();
        EXPECT_NEAR(s.finalLoss, q.minimum(), 1e-5) << s.briefReport();
        EXPECT_DOUBLE_EQ(s.finalLoss, evalAt(p, x));  // finalLoss is the loss at the returned x
        EXPECT_DOUBLE_EQ(s.initialLoss, s.history.front().loss);
        EXPECT_FALSE(s.failed) << s.termination;
        for (double xi : x) {
            EXPECT_GE(xi, 0.0);
            EXPECT_LE(xi, 1.0);
        }
        if (c.method != "adam" && c.method != "newton-tr") {
            EXPECT_LE(s.evaluations, c.iterations + 1) << s.briefReport();
        }
    }
}

namespace {

/// f(x) = ½·xᵀAx − bᵀx with A = MᵀM + I (n × n, symmetric positive definite), its gradient and
/// its exact Hessian product A·v.
Problem coupledQuadratic(size_t n, const std::vector<double>& b, std::vector<double>& a) {
    a.assign(n * n, 0.0);
    std::vector<double> m(n * n);
    uint64_t s = 12345;
    for (double& v : m) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        v = static_cast<double>(s >> 11) / 9007199254740992.0 - 0.5;
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            for (size_t k = 0; k < n; ++k) a[i * n + j] += m[k * n + i] * m[k * n + j];
            if (i == j) a[i * n + j] += 1.0;
        }
    Problem p;
    p.dimension = n;
    p.evaluate = [a, b, n](std::span<const double> x, std::span<double> g) {
        double f = 0;
        for (size_t i = 0; i < n; ++i) {
            double ax = 0;
            for (size_t j = 0; j < n; ++j) ax += a[i * n + j] * x[j];
            f += 0.5 * x[i] * ax - b[i] * x[i];
            if (!g.empty()) g[i] = ax - b[i];
        }
        return f;
    };
    p.hessianProduct = [a, n](std::span<const double>, std::span<const double> v,
                              std::span<double> hv) {
        for (size_t i = 0; i < n; ++i) {
            hv[i] = 0;
            for (size_t j = 0; j < n; ++j) hv[i] += a[i * n + j] * v[j];
        }
    };
    return p;
}

}  // namespace

TEST(Optimize, NewtonTrReachesTheAnalyticOptimumOfACoupledQuadratic) {
    // Inside the box: b = A·x* for an x* in (0.1, 0.9)ⁿ, so x* is the minimizer.
    const size_t n = 30;
    std::vector<double> xStar(n), a;
    for (size_t i = 0; i < n; ++i) xStar[i] = 0.1 + 0.8 * static_cast<double>((7 * i) % n) / n;
    std::vector<double> b(n, 0.0);
    Problem p = coupledQuadratic(n, b, a);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) b[i] += a[i * n + j] * xStar[j];
    p = coupledQuadratic(n, b, a);
    std::vector<double> x(n, 0.5);
    const OptimizerSummary s = minimize(p, x, Options("newton-tr", 100));
    EXPECT_FALSE(s.failed) << s.termination;
    // It stops at ‖x − P(x − ∇f)‖∞ <= 1e-8·max(1, |f|) (|f| ~ 18 here); A's eigenvalues are >= 1,
    // so x is within about that of x* (measured: 3.2e-8).
    EXPECT_LT(maxAbsDiff(x, xStar), 1e-6) << s.briefReport();
    EXPECT_GT(s.hessianProducts, 0);
    EXPECT_NE(s.briefReport().find("Hessian products"), std::string::npos);

    // Outside it (b pushes half the variables past a bound): the box's KKT conditions hold, and
    // the minimizer (unique: A is positive definite) is L-BFGS's to its tolerance.
    for (size_t i = 0; i < n; i += 2) b[i] += (i % 4 == 0 ? 3.0 : -3.0);
    p = coupledQuadratic(n, b, a);
    std::vector<double> xn(n, 0.5), xl(n, 0.5);
    const OptimizerSummary sn = minimize(p, xn, Options("newton-tr", 100));
    minimize(p, xl, Options("lbfgs", 2000));
    EXPECT_FALSE(sn.failed) << sn.termination;
    std::vector<double> g(n);
    const double f = p.evaluate(xn, g);
    int atBounds = 0;
    for (size_t i = 0; i < n; ++i) {
        const double pg = xn[i] - std::clamp(xn[i] - g[i], 0.0, 1.0);  // projected gradient
        EXPECT_LE(std::abs(pg), 1e-8 * std::max(1.0, std::abs(f))) << i;
        atBounds += xn[i] == 0.0 || xn[i] == 1.0;
    }
    EXPECT_GT(atBounds, 0);
    EXPECT_LT(maxAbsDiff(xn, xl), 1e-5) << sn.briefReport();
}

TEST(Optimize, NewtonTrFollowsNegativeCurvatureToTheBox) {
    // f = −Σ (x_i − 0.4)²: concave, its minimum on [0, 1]ⁿ the corner x = 1 (0.6 from 0.4).
    Problem p;
    p.dimension = 8;
    p.evaluate = [](std::span<const double> x, std::span<double> g) {
        double f = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            f -= (x[i] - 0.4) * (x[i] - 0.4);
            if (!g.empty()) g[i] = -2 * (x[i] - 0.4);
        }
        return f;
    };
    p.hessianProduct = [](std::span<const double>, std::span<const double> v,
                          std::span<double> hv) {
        for (size_t i = 0; i < v.size(); ++i) hv[i] = -2 * v[i];
    };
    std::vector<double> x(8, 0.5);
    const OptimizerSummary s = minimize(p, x, Options("newton-tr", 100));
    EXPECT_FALSE(s.failed) << s.termination;
    for (double xi : x) EXPECT_EQ(xi, 1.0);
    EXPECT_DOUBLE_EQ(s.finalLoss, -8 * 0.36);
}

TEST(Optimize, NewtonTrWithoutHessianProductsRunsLbfgsAndSaysSo) {
    const Quadratic q;
    Problem p = q.problem();
    p.hessianProduct = nullptr;
    std::vector<double> x(p.dimension, 0.5), xl(p.dimension, 0.5);
    const OptimizerSummary s = minimize(p, x, Options("newton-tr", 10));
    const OptimizerSummary l = minimize(p, xl, Options("lbfgs", 2000));
    EXPECT_EQ(s.method, "newton-tr");
    EXPECT_NE(s.settings.find("no Hessian products"), std::string::npos) << s.settings;
    EXPECT_EQ(s.hessianProducts, 0);
    EXPECT_EQ(x, xl);  // L-BFGS's iterates, with its own budget
    EXPECT_EQ(s.evaluations, l.evaluations);
}

TEST(Optimize, AdamMatchesHandComputedSteps) {
    // f(x) = 2 (x − 0.3)², x0 = 0.9, lr 0.05, β1 0.9, β2 0.999 and a large ε = 0.1 so that its
    // placement matters. Mitsuba 3: lr_t = lr·sqrt(1 − β2^t)/(1 − β1^t),
    // x ← x − lr_t·m/(sqrt(v) + ε):
    //   t=1: g = 2.4, m = 0.24, v = 0.00576, x1 = 0.9 − 0.05·(0.0316228/0.1)·0.24/(0.0758947 + 0.1)
    //          = 0.8784261039574988
    //   t=2: g = 4(x1 − 0.3) = 2.3137044158, m = 0.4473704416, v = 0.0111074681,
    //        x2 = x1 − 0.05·(sqrt(1 − 0.999²)/(1 − 0.81))·m/(sqrt(v) + 0.1) = 0.8527985817576818
    // (PyTorch's placement, ε beside sqrt(v̂), would give 0.852 and 0.80422.)
    Problem p;
    p.dimension = 1;
    p.evaluate = [](std::span<const double> x, std::span<double> g) {
        if (!g.empty()) g[0] = 4 * (x[0] - 0.3);
        return 2 * (x[0] - 0.3) * (x[0] - 0.3);
    };
    std::vector<double> seen;
    Options o("adam", 2);
    o.learningRate = 0.05;
    o.epsilon = 0.1;
    o.callback = [&](const IterationRecord&, std::span<const double> x) {
        seen.push_back(x[0]);
        return true;
    };
    std::vector<double> x = {0.9};
    const OptimizerSummary s = minimize(p, x, o);
    ASSERT_EQ(seen.size(), 3u);
    EXPECT_DOUBLE_EQ(seen[0], 0.9);
    EXPECT_NEAR(seen[1], 0.8784261039574988, 1e-14);
    EXPECT_NEAR(seen[2], 0.8527985817576818, 1e-14);
    EXPECT_NEAR(x[0], 0.8527985817576818, 1e-14);
    EXPECT_EQ(s.iterations, 2);
    EXPECT_EQ(s.evaluations, 3);  // gradients at x0, x1; the loss at x2
    EXPECT_NEAR(s.finalLoss, 2 * (x[0] - 0.3) * (x[0] - 0.3), 1e-15);
}

TEST(Optimize, AdamWithPaperSettingsStaysInBox) {
    // A linear pull out of the box on every texel (alternating directions) plus a quadratic
    // whose minimum is outside: with lr 0.02, 100 iterations, every iterate stays in [0, 1]
    // and the texels end exactly on their bounds.
    const size_t n = 50;
    Problem p;
    p.dimension = n;
    p.evaluate = [](std::span<const double> x, std::span<double> g) {
        double f = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            const double s = i % 2 ? 1.0 : -1.0;  // odd texels pushed to 0, even to 1
            f += s * x[i] + 0.5 * (x[i] - 0.5 + s) * (x[i] - 0.5 + s);
            if (!g.empty()) g[i] = s + (x[i] - 0.5 + s);
        }
        return f;
    };
    OptimizerOptions o;  // the paper: adam, lr 0.02, 100 iterations
    int outside = 0, records = 0;
    o.callback = [&](const IterationRecord&, std::span<const double> x) {
        ++records;
        for (double xi : x) outside += (xi < 0.0 || xi > 1.0);
        return true;
    };
    std::vector<double> x(n);
    for (size_t i = 0; i < n; ++i) x[i] = i % 2 ? 0.05 : 0.95;
    const OptimizerSummary s = minimize(p, x, o);
    EXPECT_EQ(outside, 0);
    EXPECT_EQ(records, 101);
    EXPECT_EQ(s.iterations, 100);
    for (size_t i = 0; i < n; ++i) EXPECT_EQ(x[i], i % 2 ? 0.0 : 1.0) << i;
}

TEST(Optimize, MlslFindsGlobalMinimumWhereLbfgsStopsInLocalOne) {
    const Problem p = wells();
    // Reference: the best point of a 1001×1001 grid (its loss is >= the true minimum).
    double gridMin = std::numeric_limits<double>::infinity();
    std::vector<double> gridArg(2);
    for (int i = 0; i <= 1000; ++i)
        for (int j = 0; j <= 1000; ++j) {
            std::vector<double> x = {i / 1000.0, j / 1000.0};
            const double f = evalAt(p, x);
            if (f < gridMin) gridMin = f, gridArg = x;
        }
    ASSERT_NEAR(gridArg[0], 0.72, 0.03);
    ASSERT_NEAR(gridArg[1], 0.78, 0.03);

    std::vector<double> xl = {0.12, 0.12};
    const OptimizerSummary sl = minimize(p, xl, Options("lbfgs", 200));
    std::vector<double> xg = {0.12, 0.12};
    Options mo("mlsl", 2000);
    mo.seed = 7;
    const OptimizerSummary sg = minimize(p, xg, mo);

    // L-BFGS: the local well at (0.2, 0.2), about 0.4 above the global minimum.
    EXPECT_NEAR(xl[0], 0.2, 0.03) << sl.briefReport();
    EXPECT_NEAR(xl[1], 0.2, 0.03) << sl.briefReport();
    EXPECT_GT(sl.finalLoss, gridMin + 0.3) << sl.briefReport();
    // MLSL: the global well, at least as good as the grid.
    EXPECT_LT(maxAbsDiff(xg, gridArg), 2e-3) << sg.briefReport();
    EXPECT_LE(sg.finalLoss, gridMin + 1e-12) << sg.briefReport();
    EXPECT_LE(sg.evaluations, 2000);
    EXPECT_FALSE(sg.failed) << sg.termination;

    // Deterministic: the same seed gives the same run.
    std::vector<double> xg2 = {0.12, 0.12};
    const OptimizerSummary sg2 = minimize(p, xg2, mo);
    EXPECT_EQ(xg2, xg);
    EXPECT_EQ(sg2.evaluations, sg.evaluations);
    EXPECT_EQ(sg2.history.size(), sg.history.size());
}

TEST(Optimize, CallbackSeesEveryIterationAndCanStop) {
    const Quadratic q;
    const Problem p = q.problem();
    for (const std::string& method : optimizerMethods()) {
        SCOPED_TRACE(method);
        // Full run: iteration 0 first, then 1, 2, ...; evaluations counted and non-decreasing.
        std::vector<IterationRecord> seen;
        Options o(method, 200);
        o.callback = [&](const IterationRecord& r, std::span<const double> x) {
            EXPECT_EQ(x.size(), p.dimension);
            seen.push_back(r);
            return true;
        };
        std::vector<double> x(p.dimension, 0.5);
        OptimizerSummary s = minimize(p, x, o);
        ASSERT_GE(seen.size(), 3u);
        EXPECT_EQ(seen.front().iteration, 0);
        EXPECT_GE(seen.front().evaluations, 1);
        for (size_t i = 1; i < seen.size(); ++i) {
            EXPECT_EQ(seen[i].iteration, seen[i - 1].iteration + 1);
            EXPECT_GE(seen[i].evaluations, seen[i - 1].evaluations);
            EXPECT_GE(seen[i].seconds, seen[i - 1].seconds);
        }
        ASSERT_EQ(seen.size(), s.history.size());
        // NLopt records improvements only, so evaluations may go on after the last record.
        if (method == "adam" || method == "ceres-lbfgs") {
            EXPECT_EQ(seen.back().evaluations, s.evaluations);
        } else {
            EXPECT_LE(seen.back().evaluations, s.evaluations);
        }
        EXPECT_EQ(seen.back().iteration, s.iterations);
        // The returned x is the best recorded iterate (the last unless an earlier was lower).
        EXPECT_EQ(s.history[static_cast<size_t>(s.returnedIteration)].loss, s.finalLoss);
        if (method != "adam") {  // NLopt/Ceres: the loss never increases along the history
            for (size_t i = 1; i < seen.size(); ++i) EXPECT_LE(seen[i].loss, seen[i - 1].loss);
        }

        // Returning false at iteration 2 stops there; x is the point the callback saw.
        std::vector<double> lastX;
        o.callback = [&](const IterationRecord& r, std::span<const double> xs) {
            lastX.assign(xs.begin(), xs.end());
            return r.iteration < 2;
        };
        x.assign(p.dimension, 0.5);
        s = minimize(p, x, o);
        EXPECT_EQ(s.termination, "stopped by callback");
        EXPECT_FALSE(s.failed);
        EXPECT_EQ(s.iterations, 2);
        EXPECT_EQ(s.history.size(), 3u);
        EXPECT_EQ(x, lastX);
        EXPECT_DOUBLE_EQ(s.finalLoss, evalAt(p, x));

        // Returning false at once: only the initial point.
        o.callback = [](const IterationRecord&, std::span<const double>) { return false; };
        x.assign(p.dimension, 0.5);
        s = minimize(p, x, o);
        EXPECT_EQ(s.iterations, 0);
        EXPECT_EQ(s.evaluations, 1);
        EXPECT_EQ(s.termination, "stopped by callback");
    }
}

// The stall stop: a window of evaluations in which the best loss fell by less than the tolerance
// ends any method ("stalled", not a failure); a tolerance of 0 never stops a run; Adam on a
// quadratic stops once it has settled, near the minimum, long before its budget.
TEST(Optimize, AWindowWithoutProgressStopsTheRun) {
    const Quadratic q;
    const Problem p = q.problem();
    for (const std::string& method : optimizerMethods()) {
        SCOPED_TRACE(method);
        Options o(method, 400);
        o.stallEvaluations = 3;
        o.stallTolerance = 1e9;  // no window can fall that much: stops at the first full window
        std::vector<double> x(p.dimension, 0.5);
        OptimizerSummary s = minimize(p, x, o);
        // (L-BFGS and TNEWTON may converge on the quadratic within the first window.)
        if (s.evaluations > 3) {
            EXPECT_EQ(s.termination.rfind("stalled", 0), 0u) << s.termination;
        }
        EXPECT_FALSE(s.failed);
        EXPECT_LE(s.evaluations, 8);  // NLopt: checked at the next improving evaluation
        EXPECT_DOUBLE_EQ(s.finalLoss, evalAt(p, x));
    }
    Options adam("adam", 20000);
    adam.stallEvaluations = 50;
    adam.stallTolerance = 0;  // off in effect: the best loss never rises
    std::vector<double> x(p.dimension, 0.5);
    OptimizerSummary s = minimize(p, x, adam);
    EXPECT_EQ(s.evaluations, 20001);
    adam.stallTolerance = 1e-9;
    x.assign(p.dimension, 0.5);
    s = minimize(p, x, adam);
    EXPECT_EQ(s.termination.rfind("stalled", 0), 0u) << s.termination;
    EXPECT_LT(s.evaluations, 20001);
    EXPECT_LT(s.finalLoss - q.minimum(), 1e-6);
}

TEST(Optimize, RejectsUnknownMethodAndBadOptions) {
    const Problem p = Quadratic().problem();
    std::vector<double> x(p.dimension, 0.5);
    try {
        minimize(p, x, Options("bfgs"));
        FAIL() << "no error";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("'bfgs'"), std::string::npos) << msg;
        for (const auto& m : optimizerMethods()) EXPECT_NE(msg.find(m), std::string::npos) << msg;
    }

    auto expectError = [&](const std::string& name, auto edit, const Problem& prob,
                           std::vector<double> start) {
        Options o("adam");
        edit(o);
        try {
            minimize(prob, start, o);
            ADD_FAILURE() << name << ": no error";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    };
    const std::vector<double> x0(p.dimension, 0.5);
    expectError(
        "iterations", [](Options& o) { o.iterations = 0; }, p, x0);
    expectError(
        "option 'learning-rate'", [](Options& o) { o.learningRate = 0; }, p, x0);
    expectError(
        "option 'learning-rate'", [](Options& o) { o.learningRate = NAN; }, p, x0);
    expectError(
        "beta1", [](Options& o) { o.beta1 = 1.0; }, p, x0);
    expectError(
        "beta2", [](Options& o) { o.beta2 = -0.1; }, p, x0);
    expectError(
        "epsilon", [](Options& o) { o.epsilon = 0; }, p, x0);
    expectError(
        "option 'relative-function-tolerance'",
        [](Options& o) { o.relativeFunctionTolerance = -1; }, p, x0);
    expectError(
        "population", [](Options& o) { o.population = -1; }, p, x0);
    Problem flat = p;
    flat.lower = flat.upper = 0.5;
    expectError(
        "bounds", [](Options&) {}, flat, x0);
    Problem empty = p;
    empty.dimension = 0;
    expectError("dimension", [](Options&) {}, empty, {});
    expectError("x has 3 values", [](Options&) {}, p, {0.1, 0.2, 0.3});
    expectError("x[1] is nan", [](Options&) {}, p, {0.1, NAN, 0.3, 0.4, 0.5, 0.6});
}

// A non-finite loss or gradient stops every method. At the start there is no finite state:
// an error naming the method and the iteration. Later the method returns the best finite
// iterate it recorded, marked failed, and says why.
TEST(Optimize, NonFiniteObjectiveStopsWithTheBestFiniteState) {
    const Quadratic q;
    for (const std::string& method : optimizerMethods()) {
        for (int badAt : {1, 4}) {  // the initial point, and a later evaluation
            for (bool inGradient : {false, true}) {
                SCOPED_TRACE(method + " at evaluation " + std::to_string(badAt) +
                             (inGradient ? " (gradient)" : " (loss)"));
                Problem p = q.problem();
                int calls = 0;
                auto inner = p.evaluate;
                p.evaluate = [&, inner](std::span<const double> x, std::span<double> g) {
                    double f = inner(x, g);
                    if (++calls >= badAt) {
                        if (!inGradient) f = std::numeric_limits<double>::quiet_NaN();
                        if (inGradient && !g.empty())
                            g[1] = std::numeric_limits<double>::infinity();
                    }
                    return f;
                };
                auto expectMessage = [&](const std::string& msg) {
                    EXPECT_NE(msg.find("'" + method + "'"), std::string::npos) << msg;
                    EXPECT_NE(msg.find("iteration"), std::string::npos) << msg;
                    EXPECT_NE(msg.find(inGradient ? "gradient" : "loss (nan)"), std::string::npos)
                        << msg;
                };
                std::vector<double> x(p.dimension, 0.5);
                try {
                    const OptimizerSummary s = minimize(p, x, Options(method, 200));
                    EXPECT_GT(badAt, 1) << "the start was not finite, yet a result came back";
                    EXPECT_TRUE(s.failed);
                    expectMessage(s.termination);
                    EXPECT_TRUE(std::isfinite(s.finalLoss));
                    EXPECT_LE(s.finalLoss, s.initialLoss);
                    EXPECT_DOUBLE_EQ(s.finalLoss, q.problem().evaluate(x, {}));
                    for (double v : x) EXPECT_TRUE(std::isfinite(v));
                } catch (const InputError& e) {
                    ADD_FAILURE() << "not an input error: " << e.what();
                } catch (const std::runtime_error& e) {
                    EXPECT_EQ(badAt, 1) << e.what();
                    expectMessage(e.what());
                }
            }
        }
    }
}

// Adam is not a descent method: at a huge λ its steps overshoot and the loss climbs. Every
// method returns the lowest-loss iterate it recorded, and says so when that is not the last.
TEST(Optimize, EveryMethodReturnsTheBestIterateItSaw) {
    Problem p;
    p.dimension = 2;
    p.evaluate = [](std::span<const double> x, std::span<double> g) {
        // A narrow valley at x = (0.3, 0.6) with a huge curvature: lr 0.2 overshoots.
        const double a = 1e6;
        if (!g.empty()) {
            g[0] = 2 * a * (x[0] - 0.3);
            g[1] = 2 * a * (x[1] - 0.6);
        }
        return a * ((x[0] - 0.3) * (x[0] - 0.3) + (x[1] - 0.6) * (x[1] - 0.6));
    };
    for (const std::string& method : optimizerMethods()) {
        SCOPED_TRACE(method);
        Options o(method, 40);
        o.learningRate = 0.2;
        std::vector<double> x{0.35, 0.55};
        const OptimizerSummary s = minimize(p, x, o);
        double lowest = s.history.front().loss;
        for (const IterationRecord& r : s.history) lowest = std::min(lowest, r.loss);
        EXPECT_DOUBLE_EQ(s.finalLoss, lowest) << s.briefReport();
        EXPECT_DOUBLE_EQ(s.finalLoss, p.evaluate(x, {}));
        const bool last = s.returnedIteration == s.history.back().iteration;
        EXPECT_EQ(last, s.termination.find("returned iteration") == std::string::npos)
            << s.termination;
        if (method == "adam") {
            EXPECT_FALSE(last) << "Adam did not climb: " << s.briefReport();
        }
    }
}

TEST(Optimize, ObjectiveExceptionsPropagateUnchanged) {
    const Quadratic q;
    for (const std::string& method : optimizerMethods()) {
        SCOPED_TRACE(method);
        Problem p = q.problem();
        int calls = 0;
        auto inner = p.evaluate;
        p.evaluate = [&, inner](std::span<const double> x, std::span<double> g) {
            if (++calls == 3) throw std::logic_error("objective exploded");
            return inner(x, g);
        };
        std::vector<double> x(p.dimension, 0.5);
        EXPECT_THROW(minimize(p, x, Options(method, 200)), std::logic_error);
    }
}

TEST(Optimize, GradientThatDoesNotMatchTheLossIsReportedNotThrown) {
    // The gradient has the wrong sign: L-BFGS's line search finds no decrease. NLopt reports a
    // failure; minimize returns the start (the best point seen) with failed set.
    Problem p;
    p.dimension = 3;
    p.evaluate = [](std::span<const double> x, std::span<double> g) {
        double f = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            f += (x[i] - 0.3) * (x[i] - 0.3);
            if (!g.empty()) g[i] = -2 * (x[i] - 0.3);
        }
        return f;
    };
    const std::vector<double> start = {0.9, 0.8, 0.7};
    std::vector<double> x = start;
    const OptimizerSummary s = minimize(p, x, Options("lbfgs", 200));
    EXPECT_TRUE(s.failed) << s.briefReport();
    EXPECT_NE(s.termination.find("NLopt failure"), std::string::npos) << s.termination;
    EXPECT_NE(s.briefReport().find("FAILED"), std::string::npos);
    EXPECT_EQ(x, start);
    EXPECT_EQ(s.finalLoss, s.initialLoss);
    EXPECT_EQ(s.iterations, 0);
}

TEST(Optimize, CeresLbfgsConvergesOn1250TexelProblemInsideTheBox) {
    // Like the real problem: 25×50 texels, separable, non-quadratic, about half of the optima
    // outside [0, 1]; some texels start exactly on a bound (the sin² map must nudge them).
    const size_t n = 1250;
    std::vector<double> a(n), c(n), x(n), solution(n);
    for (size_t i = 0; i < n; ++i) {
        const double u = std::fmod(0.6180339887 * static_cast<double>(i), 1.0);
        const double v = std::fmod(0.4142135624 * static_cast<double>(i), 1.0);
        c[i] = -0.5 + 2.0 * u;
        a[i] = 0.5 + 1.5 * v;
        solution[i] = std::clamp(c[i], 0.0, 1.0);
        x[i] = i % 7 == 0 ? 0.0 : (i % 11 == 0 ? 1.0 : 0.5);
    }
    Problem p;
    p.dimension = n;
    p.evaluate = [&](std::span<const double> xs, std::span<double> g) {
        double f = 0;
        for (size_t i = 0; i < n; ++i) {
            const double d = xs[i] - c[i];
            f += a[i] * d * d + 0.05 * d * d * d * d;
            if (!g.empty()) g[i] = 2 * a[i] * d + 0.2 * d * d * d;
        }
        return f;
    };
    double fStar = evalAt(p, solution);
    Options o("ceres-lbfgs", 500);
    int outside = 0;
    o.callback = [&](const IterationRecord&, std::span<const double> xs) {
        for (double xi : xs) outside += (xi < 0.0 || xi > 1.0);
        return true;
    };
    const OptimizerSummary s = minimize(p, x, o);
    EXPECT_EQ(outside, 0);
    EXPECT_FALSE(s.failed) << s.fullReport();
    EXPECT_LT(maxAbsDiff(x, solution), 1e-4) << s.fullReport();
    EXPECT_NEAR(s.finalLoss, fStar, 1e-6 * fStar) << s.fullReport();
    // Texels that started on a bound but whose optimum is inside did move there.
    for (size_t i = 0; i < n; i += 7)
        if (c[i] > 0.1 && c[i] < 0.9) {
            EXPECT_NEAR(x[i], c[i], 1e-4) << i;
        }
}

TEST(Optimize, ReportsDescribeTheRun) {
    const Problem p = Quadratic().problem();
    std::vector<double> x(p.dimension, 0.5);
    const OptimizerSummary s = minimize(p, x, Options("lbfgs", 100));
    const std::string brief = s.briefReport();
    EXPECT_EQ(brief.find('\n'), std::string::npos);
    EXPECT_NE(brief.find("lbfgs"), std::string::npos);
    EXPECT_NE(brief.find(std::to_string(s.evaluations) + " evaluations"), std::string::npos);
    const std::string full = s.fullReport();
    EXPECT_GE(std::count(full.begin(), full.end(), '\n'), 8);
    EXPECT_NE(full.find("Termination"), std::string::npos);
    EXPECT_NE(full.find(s.termination), std::string::npos);
}

TEST(InitialState, OneChannelEnvMapLoadsBackUnchangedAndColourGoesThroughLStar) {
    // A run's envmap.exr is one channel: it must come back as the same E (no L* curve), while
    // a colour map becomes gray by CIE L*/100 (the paper's rule for photos).
    test::TempDir dir("initial-state");
    const int W = 50, H = 25;
    EnvMap gray = EnvMap::constant(W, H, 0.0f, 1);
    for (size_t i = 0; i < gray.texels.size(); ++i)
        gray.texels[i] = static_cast<float>(i * 37 % 101) / 100.0f;
    writeEnvMap(dir.path() / "gray.exr", gray);
    std::vector<double> e = initialEnvMap(
        parseInitialState("envmap:" + (dir.path() / "gray.exr").string()), W, H, false);
    ASSERT_EQ(e.size(), gray.texels.size());
    for (size_t i = 0; i < e.size(); ++i) EXPECT_EQ(e[i], static_cast<double>(gray.texels[i]));
    std::vector<double> e3 = initialEnvMap(
        parseInitialState("envmap:" + (dir.path() / "gray.exr").string()), W, H, true);
    ASSERT_EQ(e3.size(), 3 * gray.texels.size());
    EXPECT_EQ(e3[3 * 7 + 2], static_cast<double>(gray.texels[7]));

    EnvMap rgb = EnvMap::constant(W, H, 0.18f, 3);
    writeEnvMap(dir.path() / "rgb.exr", rgb);
    std::vector<double> l = initialEnvMap(
        parseInitialState("envmap:" + (dir.path() / "rgb.exr").string()), W, H, false);
    EXPECT_NEAR(l[0], lightnessLStar01(0.18, 0.18, 0.18), 1e-6);
    EXPECT_NEAR(l[0], 0.4950, 1e-3);  // L*(Y = 0.18) = 49.50
}
