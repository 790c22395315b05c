#include "optimize/BlackBox.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "core/Color.h"
#include "core/Error.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "render/Render.h"
#include "scene/Scene.h"

namespace sl {

namespace {

/// A sink that drops the paths (for the object mask alone).
class NullSink : public PathSink {
  public:
    void consume(const PixelPaths&) override {}
};

/// Runs f(j) for j in [0, n) on `threads` workers (0: all cores), one evaluation at a time per
/// worker. Plain threads, not TBB's pool: an external renderer's process mostly waits
/// (app/host/ExternalRenderer.h), so more evaluations than cores may run at once. The first
/// exception is rethrown after every worker stopped.
template <typename F>
void parallelEvaluations(size_t n, int threads, F&& f) {
    const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
    const size_t workers = std::min(n, static_cast<size_t>(threads > 0 ? threads : hw));
    std::atomic<size_t> next{0};
    std::exception_ptr error;
    std::mutex errorMutex;
    auto work = [&] {
        for (size_t j; (j = next++) < n;) {
            try {
                f(j);
            } catch (...) {
                std::lock_guard lock(errorMutex);
                if (!error) error = std::current_exception();
                next = n;
            }
        }
    };
    std::vector<std::thread> pool;
    for (size_t k = 1; k < workers; ++k) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

double asFloat(double v) {
    return static_cast<double>(static_cast<float>(v));
}

void checkPoint(std::span<const double> E, size_t n, const char* who) {
    if (E.size() != n)
        throw std::invalid_argument(std::string(who) + ": E has " + std::to_string(E.size()) +
                                    " values, the problem " + std::to_string(n));
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(E[i]))
            throw std::invalid_argument(std::string(who) + ": E[" + std::to_string(i) +
                                        "] is not finite");
}

}  // namespace

std::vector<uint8_t> objectMaskFor(const Scene& scene, const RenderOptions& options) {
    NullSink sink;
    RenderOptions o = options;
    o.progress = {};
    return PathTracer(scene).trace(o, sink).objectMask;
}

uint64_t freshSeed(uint64_t base, uint64_t stream, uint64_t index) {
    uint64_t s = mix64(base ^ mix64(stream * 0x9e3779b97f4a7c15ULL + mix64(index + 1)));
    return s == base ? s + 1 : s;
}

RenderLoss::RenderLoss(const Scene& scene, RenderOptions options, const ImageObjective& objective,
                       bool rgb, bool interruptible)
    : envWidth_(scene.basis.width()),
      envHeight_(scene.basis.height()),
      baseSeed_(options.seed),
      threads_(options.threads),
      objective_(objective),
      rgb_(rgb),
      dimension_(static_cast<size_t>(scene.basis.texelCount()) * (rgb ? 3 : 1)) {
    options.progress = {};
    options.interruptible = interruptible;  // else Ctrl-C stops the optimizer between steps
    owned_ = std::make_unique<BuiltinRenderer>(scene, std::move(options));
    renderer_ = owned_.get();
    checkObjective();
}

RenderLoss::RenderLoss(const Renderer& renderer, int envWidth, int envHeight, uint64_t baseSeed,
                       const ImageObjective& objective, bool rgb)
    : renderer_(&renderer),
      envWidth_(envWidth),
      envHeight_(envHeight),
      baseSeed_(baseSeed),
      objective_(objective),
      rgb_(rgb),
      dimension_(static_cast<size_t>(envWidth) * envHeight * (rgb ? 3 : 1)) {
    checkObjective();
}

void RenderLoss::checkObjective() const {
    if (objective_.width() != renderer_->width() || objective_.height() != renderer_->height())
        throw std::invalid_argument(
            "RenderLoss: the objective's image size (" + std::to_string(objective_.width()) + "x" +
            std::to_string(objective_.height()) + ") differs from the renderer's");
}

std::vector<double> RenderLoss::image(std::span<const double> E, uint64_t seed, int threads) const {
    checkPoint(E, dimension_, "RenderLoss");
    EnvMap env;
    env.width = envWidth_;
    env.height = envHeight_;
    env.channels = rgb_ ? 3 : 1;
    env.texels.resize(E.size());
    for (size_t i = 0; i < E.size(); ++i) env.texels[i] = static_cast<float>(E[i]);
    const Image img = renderer_->render(env, seed, threads >= 0 ? threads : threads_);
    ++renders_;
    if (img.width != renderer_->width() || img.height != renderer_->height() || img.channels < 1)
        throw std::runtime_error("RenderLoss: renderer '" + renderer_->name() +
                                 "' returned an image of the wrong size");
    std::vector<double> Y(img.pixelCount());
    for (size_t p = 0; p < Y.size(); ++p) {
        if (img.channels >= 3) {
            const float* c = img.data.data() + p * img.channels;
            Y[p] = luminance<double>(c[0], c[1], c[2]);
        } else {
            Y[p] = img.data[p * img.channels];
        }
    }
    return Y;
}

LossParts RenderLoss::evaluate(std::span<const double> E, uint64_t seed, int threads) const {
    const std::vector<double> Y = image(E, seed, threads);
    std::vector<double> Ef(E.size());
    for (size_t i = 0; i < E.size(); ++i) Ef[i] = asFloat(E[i]);
    return objective_.evaluate(Y, Ef);
}

GradientEstimate finiteDifferenceGradient(const RenderLoss& loss, std::span<const double> E,
                                          const FdOptions& o, uint64_t stream) {
    const Stopwatch clock;
    const size_t n = loss.dimension();
    checkPoint(E, n, "finiteDifferenceGradient");
    if (!(o.h > 0) || !std::isfinite(o.h) || o.h >= 0.5)
        throw std::invalid_argument("finiteDifferenceGradient: h must be in (0, 0.5), is " +
                                    formatNumber(o.h));
    std::vector<uint32_t> texels = o.texels;
    if (texels.empty()) {
        texels.resize(n);
        for (size_t i = 0; i < n; ++i) texels[i] = static_cast<uint32_t>(i);
    }
    for (uint32_t t : texels)
        if (t >= n)
            throw std::invalid_argument("finiteDifferenceGradient: texel " + std::to_string(t) +
                                        " out of range");

    // The points: evaluation 0 is E itself; per texel a lower point a and an upper point b
    // (either may be E itself, i.e. evaluation 0).
    struct Point {
        uint32_t texel = 0;
        double value = 0;
    };
    std::vector<Point> points{{0, std::nan("")}};
    struct Quotient {
        size_t lo = 0, hi = 0;  // evaluation indices
        double step = 0;        // float(b) − float(a)
    };
    std::vector<Quotient> quotients(texels.size());
    for (size_t k = 0; k < texels.size(); ++k) {
        const uint32_t i = texels[k];
        const double e = E[i];
        double a = o.central ? e - o.h : e, b = e + o.h;
        if (b > 1.0) {  // backward near the upper bound
            b = e;
            a = e - o.h;
        } else if (a < 0.0) {  // forward near the lower bound
            a = e;
        }
        Quotient q;
        q.step = asFloat(b) - asFloat(a);
        if (asFloat(a) == asFloat(e)) {
            q.lo = 0;
        } else {
            q.lo = points.size();
            points.push_back({i, a});
        }
        if (asFloat(b) == asFloat(e)) {
            q.hi = 0;
        } else {
            q.hi = points.size();
            points.push_back({i, b});
        }
        if (!(q.step > 0))
            throw std::invalid_argument("finiteDifferenceGradient: step h = " + formatNumber(o.h) +
                                        " vanishes in float32 at E[" + std::to_string(i) +
                                        "] = " + formatNumber(e) + "; use a larger h");
        quotients[k] = q;
    }

    std::vector<double> values(points.size());
    const uint64_t base = loss.baseSeed();
    parallelEvaluations(points.size(), o.threads, [&](size_t j) {
        std::vector<double> x(E.begin(), E.end());
        if (j > 0) x[points[j].texel] = points[j].value;
        const uint64_t seed = o.commonRandomNumbers ? base : freshSeed(base, stream, j);
        values[j] = loss.evaluate(x, seed, 1).total;
    });
    for (size_t j = 0; j < values.size(); ++j)
        if (!std::isfinite(values[j]))
            throw std::runtime_error("finiteDifferenceGradient: the render's loss is not finite");

    GradientEstimate g;
    g.gradient.assign(n, 0.0);
    for (size_t k = 0; k < texels.size(); ++k) {
        const Quotient& q = quotients[k];
        g.gradient[texels[k]] = (values[q.hi] - values[q.lo]) / q.step;
    }
    g.loss = values[0];
    g.evaluations = static_cast<int>(points.size());
    g.seconds = clock.seconds();
    return g;
}

GradientEstimate spsaGradient(const RenderLoss& loss, std::span<const double> E, double c, int q,
                              Pcg32& rng, bool commonRandomNumbers, uint64_t stream, int threads,
                              std::vector<double>* estimates) {
    const Stopwatch clock;
    const size_t n = loss.dimension();
    checkPoint(E, n, "spsaGradient");
    if (!(c > 0) || !std::isfinite(c))
        throw std::invalid_argument("spsaGradient: c must be > 0, is " + formatNumber(c));
    if (q < 1) throw std::invalid_argument("spsaGradient: q must be >= 1");
    const size_t nq = static_cast<size_t>(q);

    // Rademacher perturbations, one PCG32 bit each, drawn in a fixed order.
    std::vector<int8_t> delta(nq * n);
    for (size_t k = 0; k < nq; ++k) {
        uint32_t bits = 0;
        for (size_t i = 0; i < n; ++i) {
            if (i % 32 == 0) bits = rng.nextU32();
            delta[k * n + i] = (bits & 1u) ? int8_t{1} : int8_t{-1};
            bits >>= 1;
        }
    }
    std::vector<double> values(2 * nq);
    const uint64_t base = loss.baseSeed();
    parallelEvaluations(2 * nq, threads, [&](size_t j) {
        const size_t k = j / 2;
        const double s = (j % 2 == 0) ? c : -c;
        std::vector<double> x(n);
        for (size_t i = 0; i < n; ++i) x[i] = E[i] + s * delta[k * n + i];
        const uint64_t seed = commonRandomNumbers ? base : freshSeed(base, stream, j);
        values[j] = loss.evaluate(x, seed, 1).total;
    });

    GradientEstimate g;
    g.gradient.assign(n, 0.0);
    if (estimates) estimates->assign(nq * n, 0.0);
    double lossSum = 0;
    for (size_t k = 0; k < nq; ++k) {
        const double lp = values[2 * k], lm = values[2 * k + 1];
        if (!std::isfinite(lp) || !std::isfinite(lm))
            throw std::runtime_error("spsaGradient: the render's loss is not finite");
        const double d = (lp - lm) / (2.0 * c);
        lossSum += 0.5 * (lp + lm);
        for (size_t i = 0; i < n; ++i) {
            const double gi = d * delta[k * n + i];  // Δ_i⁻¹ = Δ_i for ±1
            g.gradient[i] += gi / static_cast<double>(nq);
            if (estimates) (*estimates)[k * n + i] = gi;
        }
    }
    g.loss = lossSum / static_cast<double>(nq);
    g.evaluations = static_cast<int>(2 * nq);
    g.seconds = clock.seconds();
    return g;
}

namespace {

void validateCommon(const RenderLoss& loss, const std::vector<double>& E,
                    const OptimizerOptions& o) {
    if (o.iterations < 1)
        throw inputError("optimizer option 'iterations'", "is " + std::to_string(o.iterations),
                         "use a count >= 1");
    if (!(o.learningRate > 0) || !std::isfinite(o.learningRate))
        throw inputError("optimizer option 'learningRate'", "is " + formatNumber(o.learningRate),
                         "use a finite value > 0 (default 0.02)");
    if (E.size() != loss.dimension())
        throw inputError("optimizer start point",
                         "E has " + std::to_string(E.size()) + " values, the problem " +
                             std::to_string(loss.dimension()),
                         "pass one value per texel");
    for (size_t i = 0; i < E.size(); ++i)
        if (!std::isfinite(E[i]))
            throw inputError("optimizer start point", "E[" + std::to_string(i) + "] is not finite",
                             "start from finite values");
}

std::string fdSettings(const FdOptions& fd) {
    return std::string("finite differences: ") + (fd.central ? "central" : "forward") + ", h " +
           formatNumber(fd.h) + ", " +
           (fd.commonRandomNumbers ? "common random numbers" : "fresh seeds");
}

OptimizerSummary minimizeFdAdam(const RenderLoss& loss, std::vector<double>& E,
                                const OptimizerOptions& options, const FdOptions& fd) {
    if (!(fd.h > 0) || !std::isfinite(fd.h) || fd.h >= 0.5)
        throw inputError("finite-difference option 'h'", "is " + formatNumber(fd.h),
                         "use a step in (0, 0.5), e.g. 1e-3");
    const long renders0 = loss.renders();
    std::vector<long> rendersAfter;  // renders after the k-th problem evaluation
    uint64_t stream = 0;
    Problem p;
    p.dimension = loss.dimension();
    p.lower = 0.0;
    p.upper = 1.0;
    p.evaluate = [&](std::span<const double> x, std::span<double> grad) {
        double value;
        if (grad.empty()) {
            value = loss.evaluate(x, loss.baseSeed(), fd.threads).total;
        } else {
            GradientEstimate g = finiteDifferenceGradient(loss, x, fd, stream++);
            std::copy(g.gradient.begin(), g.gradient.end(), grad.begin());
            value = g.loss;
        }
        rendersAfter.push_back(loss.renders() - renders0);
        return value;
    };
    auto rendersAt = [&](int evaluations) {
        return evaluations <= 0 ? 0 : static_cast<int>(rendersAfter[evaluations - 1]);
    };
    OptimizerOptions o = options;
    o.method = OptimizerMethod::Adam;
    if (options.callback) {
        o.callback = [&](const IterationRecord& r, std::span<const double> x) {
            IterationRecord rr = r;
            rr.evaluations = rendersAt(r.evaluations);
            return options.callback(rr, x);
        };
    }
    OptimizerSummary s = minimize(p, E, o);
    for (IterationRecord& r : s.history) r.evaluations = rendersAt(r.evaluations);
    s.method = methodName(OptimizerMethod::FdAdam);
    s.evaluations = static_cast<int>(loss.renders() - renders0);
    s.settings = fdSettings(fd) + "; Adam " + s.settings + "; evaluations = renders";
    return s;
}

OptimizerSummary minimizeSpsa(const RenderLoss& loss, std::vector<double>& E,
                              const OptimizerOptions& options, const SpsaOptions& sp) {
    auto bad = [](const std::string& field, double v, const std::string& fix) {
        return inputError("SPSA option '" + field + "'", "is " + formatNumber(v), fix);
    };
    if (!(sp.c > 0) || !std::isfinite(sp.c)) throw bad("c", sp.c, "use a value > 0, e.g. 0.02");
    if (sp.q < 1) throw bad("q", sp.q, "use a count >= 1");
    if (!(sp.alpha > 0) || !std::isfinite(sp.alpha))
        throw bad("alpha", sp.alpha, "use Spall's 0.602 (or 1)");
    if (!(sp.gamma > 0) || !std::isfinite(sp.gamma))
        throw bad("gamma", sp.gamma, "use Spall's 0.101 (or 1/6)");
    if (!std::isfinite(sp.a)) throw bad("a", sp.a, "use a finite gain, or 0 to calibrate");
    if (!std::isfinite(sp.A)) throw bad("A", sp.A, "use a value >= 0, or < 0 for 10 %");
    if (sp.a <= 0 && sp.calibrationEstimates < 1)
        throw bad("calibrationEstimates", sp.calibrationEstimates, "use a count >= 1");

    const Stopwatch clock;
    const long renders0 = loss.renders();
    const size_t n = E.size();
    for (double& e : E) e = std::clamp(e, 0.0, 1.0);
    OptimizerSummary s;
    s.method = methodName(OptimizerMethod::Spsa);
    s.dimension = n;
    s.lower = 0;
    s.upper = 1;
    std::vector<double> lastX, bestX;  // bestX: the lowest estimate between the exact ends
    double bestEstimate = std::numeric_limits<double>::infinity();
    auto record = [&](int iteration, double value, const std::vector<double>& x) {
        if (!std::isfinite(value))
            throw std::runtime_error(
                "minimize (method 'spsa'): the loss is not finite at "
                "iteration " +
                std::to_string(iteration) + "; stopping");
        IterationRecord r;
        r.iteration = iteration;
        r.evaluations = static_cast<int>(loss.renders() - renders0);
        r.loss = value;
        r.seconds = clock.seconds();
        s.history.push_back(r);
        lastX = x;
        if (iteration > 0 && value < bestEstimate) {
            bestEstimate = value;
            bestX = x;
        }
        return !options.callback || options.callback(r, x);
    };

    const double A = sp.A >= 0 ? sp.A : 0.1 * options.iterations;
    Pcg32 rng(sp.seed, 0x5b5a5a5a5a5a5a5bULL);
    uint64_t stream = 0;
    const uint64_t base = loss.baseSeed();

    const std::vector<double> firstX = E;
    bool stopped = !record(0, loss.evaluate(E, base, sp.threads).total, E);
    double a = sp.a;
    if (!stopped && a <= 0) {
        GradientEstimate g0 = spsaGradient(loss, E, sp.c, sp.calibrationEstimates, rng,
                                           sp.commonRandomNumbers, stream++, sp.threads);
        double meanAbs = 0;
        for (double v : g0.gradient) meanAbs += std::abs(v);
        meanAbs /= static_cast<double>(n);
        a = meanAbs > 0 ? options.learningRate * std::pow(A + 1.0, sp.alpha) / meanAbs
                        : options.learningRate;
    }
    s.settings = "a " + formatNumber(a) + (sp.a <= 0 ? " (calibrated)" : "") + ", c " +
                 formatNumber(sp.c) + ", A " + formatNumber(A) + ", alpha " +
                 formatNumber(sp.alpha) + ", gamma " + formatNumber(sp.gamma) + ", q " +
                 std::to_string(sp.q) + ", " +
                 (sp.commonRandomNumbers ? "common random numbers" : "fresh seeds") +
                 ", E projected to [0, 1]; evaluations = renders";

    int k = 0;
    for (; !stopped && k < options.iterations; ++k) {
        const double ak = a / std::pow(k + 1.0 + A, sp.alpha);
        const double ck = sp.c / std::pow(k + 1.0, sp.gamma);
        GradientEstimate g =
            spsaGradient(loss, E, ck, sp.q, rng, sp.commonRandomNumbers, stream++, sp.threads);
        if (k > 0 && !record(k, g.loss, E)) {
            stopped = true;
            break;
        }
        for (size_t i = 0; i < n; ++i) E[i] = std::clamp(E[i] - ak * g.gradient[i], 0.0, 1.0);
    }
    if (stopped) {
        E = lastX;
        s.termination = "stopped by callback";
    } else {
        record(k, loss.evaluate(E, base, sp.threads).total, E);
        s.termination = "iteration limit reached (" + std::to_string(options.iterations) + ")";
    }
    s.iterations = s.history.back().iteration;
    s.initialLoss = s.history.front().loss;
    s.finalLoss = s.history.back().loss;
    s.returnedIteration = s.iterations;
    // The best iterate: the exact ends, or the iterate whose free estimate was lowest, scored
    // exactly (one more render) when that estimate undercuts both.
    const double lastExact = s.finalLoss;
    if (!bestX.empty() && bestEstimate < std::min(s.initialLoss, s.finalLoss)) {
        const double exact = loss.evaluate(bestX, base, sp.threads).total;
        if (std::isfinite(exact) && exact < s.finalLoss) {
            E = bestX;
            s.finalLoss = exact;
            for (const IterationRecord& r : s.history)
                if (r.loss == bestEstimate) s.returnedIteration = r.iteration;
        }
    }
    if (s.initialLoss < s.finalLoss) {
        E = firstX;
        s.finalLoss = s.initialLoss;
        s.returnedIteration = 0;
    }
    if (s.returnedIteration != s.iterations)
        s.termination += "; returned iteration " + std::to_string(s.returnedIteration) +
                         ", the lowest loss seen (the last was " + formatNumber(lastExact) + ")";
    s.evaluations = static_cast<int>(loss.renders() - renders0);
    s.seconds = clock.seconds();
    return s;
}

}  // namespace

OptimizerSummary minimizeBlackBox(const RenderLoss& loss, std::vector<double>& E,
                                  const OptimizerOptions& options,
                                  const BlackBoxOptions& blackBox) {
    if (methodRow(options.method).gradient != GradientSource::Renderer) {
        std::string list;
        for (const std::string& m : blackBoxMethods()) list += (list.empty() ? "" : ", ") + m;
        throw inputError(
            "optimizer method",
            std::string("'") + methodName(options.method) + "' is not a black-box method",
            "use one of: " + list);
    }
    validateCommon(loss, E, options);
    if (options.method == OptimizerMethod::FdAdam)
        return minimizeFdAdam(loss, E, options, blackBox.fd);
    return minimizeSpsa(loss, E, options, blackBox.spsa);
}

}  // namespace sl
