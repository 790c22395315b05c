#include "objective/TransportLoss.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/Error.h"

namespace sl {

TransportLoss::TransportLoss(const TransportMatrix& t, const ImageObjective& objective, bool rgb)
    : t_(t), obj_(&objective), dimension_(t.cols() * (rgb ? 3 : 1)), y_(t.rows()), dLdY_(t.rows()) {
    if (rgb && t.channels != 3)
        throw std::invalid_argument("an RGB env map needs an RGB transport matrix (" +
                                    option("rgb") + ")");
    if (static_cast<size_t>(objective.width()) * objective.height() != t.rows())
        throw std::invalid_argument("objective image size != transport matrix rows");
}

TransportLoss::TransportLoss(const TransportMatrix& t, const HalfImageObjective& objective,
                             bool rgb)
    : t_(t),
      unb_(&objective),
      dimension_(t.cols() * (rgb ? 3 : 1)),
      y_(t.rows()),
      dLdY_(t.rows()),
      yb_(t.rows()),
      dLdYb_(t.rows()) {
    if (rgb && t.channels != 3)
        throw std::invalid_argument("an RGB env map needs an RGB transport matrix (" +
                                    option("rgb") + ")");
    if (t.planes != 2)
        throw std::invalid_argument(
            "this objective needs the two halves of T (precompute with two sample sets)");
    if (static_cast<size_t>(objective.imageWidth()) * objective.imageHeight() != t.rows())
        throw std::invalid_argument("objective image size != transport matrix rows");
}

LossParts TransportLoss::evaluateUnbiased(std::span<const double> E, std::span<double> grad) const {
    t_.applyLuminanceHalves(E, y_, yb_);
    shard_.gatherImage(y_, t_.width);
    shard_.gatherImage(yb_, t_.width);
    if (grad.empty()) return unb_->evaluate(y_, yb_, E);
    std::vector<double> dLdE(dimension_);
    LossParts parts = unb_->evaluate(y_, yb_, E, dLdY_, dLdYb_, dLdE);
    t_.applyTransposeLuminanceHalves(dLdY_, dLdYb_, grad);
    if (distributed()) shard_.ranks->sum(grad);
    for (size_t i = 0; i < dimension_; ++i) grad[i] += dLdE[i];
    return parts;
}

LossParts TransportLoss::evaluate(std::span<const double> E, std::span<double> grad) const {
    if (E.size() != dimension_) throw std::invalid_argument("TransportLoss: E has the wrong size");
    if (unb_) {
        if (!grad.empty() && grad.size() != dimension_)
            throw std::invalid_argument("TransportLoss: gradient has the wrong size");
        return evaluateUnbiased(E, grad);
    }
    t_.applyLuminance(E, y_);
    shard_.gatherImage(y_, t_.width);
    if (grad.empty()) return obj_->evaluate(y_, E);
    if (grad.size() != dimension_)
        throw std::invalid_argument("TransportLoss: gradient has the wrong size");
    std::vector<double> dLdE(dimension_);
    LossParts parts = obj_->evaluate(y_, E, dLdY_, dLdE);
    t_.applyTransposeLuminance(dLdY_, grad);
    if (distributed()) shard_.ranks->sum(grad);
    for (size_t i = 0; i < dimension_; ++i) grad[i] += dLdE[i];
    return parts;
}

LossParts TransportLoss::evaluateFused(std::span<const double> E, std::span<double> grad) const {
    if (E.size() != dimension_) throw std::invalid_argument("TransportLoss: E has the wrong size");
    if (grad.empty() || unb_ || distributed()) return evaluate(E, grad);
    if (grad.size() != dimension_)
        throw std::invalid_argument("TransportLoss: gradient has the wrong size");
    const int W = t_.width, H = t_.height;
    const size_t w = static_cast<size_t>(W), n = dimension_;
    const bool rgbE = dimension_ == 3 * t_.cols();
    const double regScale = obj_->imageRegScale();
    const int chunkRows = std::max(16, (H + 15) / 16), band = 2;
    const int nChunks = (H + chunkRows - 1) / chunkRows;
    std::vector<double> gs(static_cast<size_t>(nChunks) * n, 0.0);
    std::vector<double> gy(regScale != 0 ? static_cast<size_t>(nChunks) * n : 0, 0.0);

    auto chunk = [&](int k) {
        const int a = k * chunkRows, b = std::min(H, a + chunkRows);
        const int lo = std::max(a - 1, 0), hi = std::min(b + 1, H);
        thread_local std::vector<double> yl, sl;
        yl.assign(static_cast<size_t>(hi - lo) * w, 0.0);
        sl.assign(static_cast<size_t>(hi - lo) * w, 0.0);
        auto rowOf = [&](std::vector<double>& v, int y) { return v.data() + (y - lo) * w; };
        int computed = lo;  // rows [lo, computed) of yl hold Y
        auto ensureY = [&](int upto) {
            if (upto <= computed) return;
            t_.applyLuminanceRows(E.data(), rgbE, rowOf(yl, computed), computed * w, upto * w);
            computed = upto;
        };
        if (a > 0) {  // the vertical pairs (a-1, a) that the previous chunk owns touch row a
            ensureY(a + 1);
            obj_->accumulateSignsRows(yl.data(), sl.data(), a - 1, a, lo);
        }
        double* gsk = gs.data() + static_cast<size_t>(k) * n;
        double* gyk = gy.empty() ? nullptr : gy.data() + static_cast<size_t>(k) * n;
        for (int y0 = a; y0 < b; y0 += band) {
            const int y1 = std::min(y0 + band, b);
            ensureY(std::min(y1 + 1, hi));
            obj_->accumulateSignsRows(yl.data(), sl.data(), y0, y1, lo);
            // Rows [y0, y1) now have their final s; their T rows were just read for Y.
            t_.accumulateTransposeRows(rowOf(sl, y0), rgbE, gsk, y0 * w, y1 * w);
            if (gyk) t_.accumulateTransposeRows(rowOf(yl, y0), rgbE, gyk, y0 * w, y1 * w);
            std::copy(rowOf(yl, y0), rowOf(yl, y1), y_.data() + y0 * w);
        }
    };
    auto run = [&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, nChunks, 1),
            [&](const tbb::blocked_range<int>& r) {
                for (int k = r.begin(); k < r.end(); ++k) chunk(k);
            },
            tbb::simple_partitioner());
    };
    if (t_.threads > 0) {
        tbb::task_arena arena(t_.threads);
        arena.execute(run);
    } else {
        run();
    }

    // The values (and the env-map regulariser's gradient) from the objective itself.
    std::vector<double> dLdE(dimension_);
    LossParts parts = obj_->evaluate(y_, E, {}, dLdE);
    const double scale = obj_->lGradScale(parts.G);
    for (size_t i = 0; i < n; ++i) {
        double s = 0, yy = 0;
        for (int k = 0; k < nChunks; ++k) {
            s += gs[static_cast<size_t>(k) * n + i];
            if (!gy.empty()) yy += gy[static_cast<size_t>(k) * n + i];
        }
        grad[i] = scale * s + regScale * yy + dLdE[i];
    }
    return parts;
}

LossParts TransportLoss::evaluateOnColumns(const TransportColumns& columns,
                                           std::span<const double> E,
                                           std::span<const uint16_t> active,
                                           std::span<double> grad) const {
    if (E.size() != dimension_ || dimension_ != t_.cols())
        throw std::invalid_argument("TransportLoss::evaluateOnColumns: needs a gray E");
    if (distributed())
        throw std::logic_error("TransportLoss::evaluateOnColumns: not over distributed ranks");
    if (columns.rows() != t_.rows() || columns.cols() != t_.cols() || columns.planes() != t_.planes)
        throw std::invalid_argument("TransportLoss::evaluateOnColumns: columns of another T");
    if (!grad.empty() && grad.size() != dimension_)
        throw std::invalid_argument("TransportLoss: gradient has the wrong size");
    std::vector<double> dLdE(grad.empty() ? 0 : dimension_);
    LossParts parts;
    if (unb_) {
        columns.applyHalves(E, active, y_, yb_);
        if (grad.empty()) return unb_->evaluate(y_, yb_, E);
        parts = unb_->evaluate(y_, yb_, E, dLdY_, dLdYb_, dLdE);
        std::copy(dLdE.begin(), dLdE.end(), grad.begin());
        std::vector<double> tg(dimension_, 0.0);
        columns.transposeHalves(dLdY_, dLdYb_, active, tg);
        for (uint16_t c : active) grad[c] += tg[c];
        return parts;
    }
    columns.apply(E, active, y_);
    if (grad.empty()) return obj_->evaluate(y_, E);
    parts = obj_->evaluate(y_, E, dLdY_, dLdE);
    std::copy(dLdE.begin(), dLdE.end(), grad.begin());
    std::vector<double> tg(dimension_, 0.0);
    columns.transpose(dLdY_, active, tg);
    for (uint16_t c : active) grad[c] += tg[c];
    return parts;
}

std::vector<double> TransportLoss::image(std::span<const double> E) const {
    std::vector<double> y(t_.rows());
    t_.applyLuminance(E, y);  // T = (T_a + T_b)/2 for halves
    shard_.gatherImage(y, t_.width);
    return y;
}

Problem TransportLoss::problem(LossParts* last, bool fused) const {
    Problem p;
    p.dimension = dimension_;
    p.lower = 0.0;
    p.upper = 1.0;
    p.evaluate = [this, last, fused](std::span<const double> x, std::span<double> g) {
        LossParts parts = fused ? evaluateFused(x, g) : evaluate(x, g);
        if (last) *last = parts;
        return parts.total;
    };
    return p;
}

CyclingLoss::CyclingLoss(std::vector<const TransportLoss*> losses) : losses_(std::move(losses)) {
    if (losses_.empty()) throw std::invalid_argument("CyclingLoss: no loss");
    for (const TransportLoss* l : losses_)
        if (!l || l->dimension() != losses_.front()->dimension())
            throw std::invalid_argument("CyclingLoss: losses of different dimensions");
}

LossParts CyclingLoss::evaluate(std::span<const double> E, std::span<double> grad) {
    if (!grad.empty()) {
        const TransportLoss& l = *losses_[next_];
        next_ = (next_ + 1) % losses_.size();
        return l.evaluateFused(E, grad);
    }
    LossParts mean;
    const double w = 1.0 / static_cast<double>(losses_.size());
    for (const TransportLoss* l : losses_) {
        const LossParts p = l->evaluate(E, {});
        mean.total += w * p.total;
        mean.lGrad += w * p.lGrad;
        mean.lReg += w * p.lReg;
        mean.G += w * p.G;
        mean.S = p.S;
        mean.clamped = mean.clamped || p.clamped;
    }
    return mean;
}

Problem CyclingLoss::problem(LossParts* last) {
    Problem p;
    p.dimension = dimension();
    p.lower = 0.0;
    p.upper = 1.0;
    p.evaluate = [this, last](std::span<const double> x, std::span<double> g) {
        LossParts parts = evaluate(x, g);
        if (last) *last = parts;
        return parts.total;
    };
    return p;
}

}  // namespace sl
