#include "objective/TransportLoss.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "core/Error.h"
#include "core/Hash.h"

namespace sl {

namespace {

/// Σ v², eight lanes at a time (vectorised; the order is fixed).
double sumOfSquares(const double* v, size_t n) {
    double acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    size_t i = 0;
    for (; i + 8 <= n; i += 8)
        for (int l = 0; l < 8; ++l) acc[l] += v[i + l] * v[i + l];
    for (; i < n; ++i) acc[0] += v[i] * v[i];
    return ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]));
}

}  // namespace

struct TransportLoss::SlicesCache {
    std::once_flag once;
    std::unique_ptr<TransportSlices> slices;
};

struct TransportLoss::GramCache {
    std::once_flag once, decided;
    std::shared_ptr<const TransportGram> gram;
    std::atomic<bool> ready{false};  // gram is set (read without the once flag)
    bool pays = false;
    bool fits = false;  // the matrices within kGramMaxBytes
    double work = 0;    // TransportGram::buildWork
};

namespace {

/// The Gram matrices of one T for one pair mask, shared by every loss on that T in the process
/// while any of them lives (a lamps run's E* search and its fit, the viewer's searches): built
/// once, not once per loss. Keyed by the matrix's identity and size and the mask's values.
struct GramKey {
    const TransportMatrix* t = nullptr;
    size_t nnz = 0;
    std::vector<uint8_t> mask;
    bool products = false;
    bool operator==(const GramKey&) const = default;
};
std::mutex gramRegistryMutex;
std::vector<std::pair<GramKey, std::weak_ptr<const TransportGram>>> gramRegistry;

/// The registry's Gram for (t, mask, products): a live one, else `adopt` when given (matrices
/// built before), else one built now.
std::shared_ptr<const TransportGram> sharedGram(const TransportMatrix& t,
                                                std::span<const uint8_t> mask, bool products,
                                                std::shared_ptr<const TransportGram> adopt = {}) {
    GramKey key{&t, t.nnz(), std::vector<uint8_t>(mask.begin(), mask.end()), products};
    const std::lock_guard lock(gramRegistryMutex);
    std::erase_if(gramRegistry, [](const auto& e) { return e.second.expired(); });
    for (const auto& [k, g] : gramRegistry)
        if (k == key)
            if (auto shared = g.lock()) return shared;
    auto g = adopt ? std::move(adopt)
                   : std::make_shared<const TransportGram>(t, mask, products, t.threads);
    gramRegistry.emplace_back(std::move(key), g);
    return g;
}

/// The registry's live Gram for (t, mask, products), or null.
std::shared_ptr<const TransportGram> liveGram(const TransportMatrix& t,
                                              std::span<const uint8_t> mask, bool products) {
    const GramKey key{&t, t.nnz(), std::vector<uint8_t>(mask.begin(), mask.end()), products};
    const std::lock_guard lock(gramRegistryMutex);
    for (const auto& [k, g] : gramRegistry)
        if (k == key)
            if (auto shared = g.lock()) return shared;
    return nullptr;
}

/// The revision of TransportGram's build (its sums' order): a stored Gram of another revision
/// is not read (gramKey). 2: Lap·T_b's rows merged before they are added (TransportGram.h).
constexpr int kGramRevision = 2;

}  // namespace

TransportLoss::TransportLoss(const TransportMatrix& t, const ImageObjective& objective, bool rgb)
    : t_(t),
      obj_(&objective),
      dimension_(t.cols() * (rgb ? 3 : 1)),
      y_(t.rows()),
      dLdY_(t.rows()),
      slices_(std::make_shared<SlicesCache>()),
      gram_(std::make_shared<GramCache>()) {
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
      dLdYb_(t.rows()),
      slices_(std::make_shared<SlicesCache>()),
      gram_(std::make_shared<GramCache>()) {
    if (rgb && t.channels != 3)
        throw std::invalid_argument("an RGB env map needs an RGB transport matrix (" +
                                    option("rgb") + ")");
    if (t.planes != 2)
        throw std::invalid_argument(
            "this objective needs the two halves of T (precompute with two sample sets)");
    if (static_cast<size_t>(objective.imageWidth()) * objective.imageHeight() != t.rows())
        throw std::invalid_argument("objective image size != transport matrix rows");
}

const TransportSlices* TransportLoss::productSlices() const {
    switch (layout_) {
        case TransportLayout::Csr:
            return nullptr;
        case TransportLayout::Slices:
            return &slices();
        case TransportLayout::Auto:
        case TransportLayout::Gram:
            if (t_.bytes() > kAutoSlicesMaxBytes) return nullptr;
            return evaluations_++ < kAutoSlicesAfter ? nullptr : &slices();
    }
    return nullptr;
}

void TransportLoss::Products::luminance(std::span<const double> E, std::span<double> y) const {
    if (slices)
        slices->applyLuminance(E, y, TransportMatrix::kMeanPlane, t.threads);
    else
        t.applyLuminance(E, y);
}

void TransportLoss::Products::luminanceHalves(std::span<const double> E, std::span<double> ya,
                                              std::span<double> yb) const {
    if (slices)
        slices->applyLuminanceHalves(E, ya, yb, t.threads);
    else
        t.applyLuminanceHalves(E, ya, yb);
}

void TransportLoss::Products::transpose(std::span<const double> dy, std::span<double> g) const {
    if (slices)
        slices->applyTransposeLuminance(dy, g, TransportMatrix::kMeanPlane, t.threads);
    else
        t.applyTransposeLuminance(dy, g);
}

void TransportLoss::Products::transposeHalves(std::span<const double> dya,
                                              std::span<const double> dyb,
                                              std::span<double> g) const {
    if (slices)
        slices->applyTransposeLuminanceHalves(dya, dyb, g, t.threads);
    else
        t.applyTransposeLuminanceHalves(dya, dyb, g);
}

bool TransportLoss::gramEligible() const {
    return unb_ && unb_->quadraticInHalves() && dimension_ == t_.cols() && !distributed() &&
           t_.storage == TransportStorage::Sparse && t_.planes == 2;
}

bool TransportLoss::gramPays() const {
    if (!gramEligible()) return false;
    decideGram();
    return gram_->pays;
}

void TransportLoss::decideGram() const {
    std::call_once(gram_->decided, [&] {
        const double n = static_cast<double>(t_.cols());
        const double matrices = unb_->usesProducts() ? 2 : 1;
        gram_->fits = matrices * n * n * static_cast<double>(sizeof(double)) <=
                      static_cast<double>(kGramMaxBytes);
        gram_->work = TransportGram::buildWork(t_, unb_->pairMask(), unb_->usesProducts());
        gram_->pays =
            gram_->fits && gram_->work <= kGramWorkPerNonZero * static_cast<double>(t_.nnz());
    });
}

bool TransportLoss::gramRepaid(int evaluations) const {
    if (!gramEligible()) return false;
    decideGram();
    return gram_->fits && gram_->work <= kGramWorkPerEvaluation * static_cast<double>(t_.nnz()) *
                                             static_cast<double>(evaluations);
}

const TransportGram& TransportLoss::gram() const {
    if (!gramEligible())
        throw std::logic_error("TransportLoss::gram: the loss is not quadratic in T's halves");
    std::call_once(gram_->once, [&] {
        gram_->gram = sharedGram(t_, unb_->pairMask(), unb_->usesProducts());
        gram_->ready = true;
    });
    return *gram_->gram;
}

std::string TransportLoss::gramKey(const std::string& fingerprint) const {
    if (!gramEligible())
        throw std::logic_error("TransportLoss::gramKey: the loss is not quadratic in T's halves");
    const std::span<const uint8_t> mask = unb_->pairMask();
    std::ostringstream what;
    what << "gram " << kGramRevision << "; T " << fingerprint << "; " << t_.rows() << "x"
         << t_.cols() << ", nnz " << t_.nnz() << ", channels " << t_.channels << "; products "
         << unb_->usesProducts() << "; pairs " << toHex(hash64(mask.data(), mask.size()));
    const std::string w = what.str();
    return hexKey128(w);
}

bool TransportLoss::adoptGram(std::shared_ptr<const TransportGram> g) const {
    if (!g || !gramEligible() || g->cols() != t_.cols() ||
        (unb_->usesProducts() && !g->hasProducts()))
        return false;
    bool adopted = false;
    std::call_once(gram_->once, [&] {
        gram_->gram = sharedGram(t_, unb_->pairMask(), unb_->usesProducts(), std::move(g));
        gram_->ready = true;
        adopted = true;
    });
    return adopted;
}

bool TransportLoss::shareHeldGram() const {
    if (!gramEligible() || gram_->ready) return gram_->ready;
    auto held = liveGram(t_, unb_->pairMask(), unb_->usesProducts());
    return held && adoptGram(std::move(held));
}

std::shared_ptr<const TransportGram> TransportLoss::gramIfBuilt() const {
    return gram_->ready ? gram_->gram : nullptr;
}

const TransportGram* TransportLoss::evaluationGram() const {
    if (!gramEligible()) return nullptr;
    if (layout_ == TransportLayout::Gram) return &gram();
    // Auto: at once when this loss has its Gram already (built for it or adopted: nothing left
    // to pay); from the kAutoSlicesAfter-th evaluation when the build pays (gramPays); else once
    // the evaluations so far have cost what the build will (gramRepaid).
    if (layout_ != TransportLayout::Auto) return nullptr;
    if (gram_->ready) return &gram();
    if (evaluations_ < kAutoSlicesAfter) return nullptr;
    return gramPays() || gramRepaid(evaluations_) ? &gram() : nullptr;
}

LossParts TransportLoss::evaluateGram(const TransportGram& g, std::span<const double> E,
                                      std::span<const uint16_t> active, bool onActive,
                                      std::span<double> grad) const {
    const bool want = !grad.empty(), products = unb_->usesProducts();
    pe_.resize(want ? dimension_ : 0);
    qe_.resize(want && products ? dimension_ : 0);
    peAt_.clear();
    const double G = onActive ? g.pairFormOn(E, active, pe_) : g.pairForm(E, pe_, t_.threads);
    if (want && !onActive) {  // P·E whole at E: a Hessian product at E reads it
        peAt_.assign(E.begin(), E.end());
        gAt_ = G;
    }
    const double R = !products  ? 0.0
                     : onActive ? g.productFormOn(E, active, qe_)
                                : g.productForm(E, qe_, t_.threads);
    double dLdG = 0, dLdR = 0;
    const LossParts parts = unb_->fromForms(G, R, E, dLdG, dLdR, grad);
    if (!want) return parts;
    // ∇G = 2·P·E, ∇R = 2·Q·E (P, Q symmetric); grad holds dLoss/dE of the regulariser.
    auto add = [&](size_t i) {
        grad[i] += 2 * dLdG * pe_[i] + (products ? 2 * dLdR * qe_[i] : 0.0);
    };
    if (onActive)
        for (uint16_t c : active) add(c);
    else
        for (size_t i = 0; i < dimension_; ++i) add(i);
    return parts;
}

bool TransportLoss::offersHessian() const {
    if (!gramEligible()) return false;
    const double n = static_cast<double>(t_.cols()), matrices = unb_->usesProducts() ? 2 : 1;
    return matrices * n * n * static_cast<double>(sizeof(double)) <=
           static_cast<double>(kGramMaxBytes);
}

void TransportLoss::hessianProduct(std::span<const double> E, std::span<const double> v,
                                   std::span<double> Hv) const {
    if (E.size() != dimension_ || v.size() != dimension_ || Hv.size() != dimension_)
        throw std::invalid_argument("TransportLoss::hessianProduct: E, v or Hv has the wrong size");
    const TransportGram& g = gram();
    const bool products = unb_->usesProducts();
    if (peAt_.size() != dimension_ || !std::equal(E.begin(), E.end(), peAt_.begin())) {
        pe_.resize(dimension_);
        gAt_ = g.pairForm(E, pe_, t_.threads);
        peAt_.assign(E.begin(), E.end());
    }
    double dLdG = 0, dLdR = 0, d2LdG2 = 0, regCurvature = 0;
    unb_->fromForms(gAt_, 0.0, E, dLdG, dLdR, {});  // dLdR does not depend on R
    unb_->formCurvature(gAt_, dimension_, d2LdG2, regCurvature);
    hp_.resize(dimension_);
    g.pairForm(v, hp_, t_.threads);
    if (products) {
        hq_.resize(dimension_);
        g.productForm(v, hq_, t_.threads);
    }
    double pev = 0;  // (P·E)ᵀ·v
    for (size_t i = 0; i < dimension_; ++i) pev += pe_[i] * v[i];
    const double a = 2 * dLdG, b = 4 * d2LdG2 * pev, c = 2 * dLdR;
    for (size_t i = 0; i < dimension_; ++i)
        Hv[i] = a * hp_[i] + b * pe_[i] + regCurvature * v[i] + (products ? c * hq_[i] : 0.0);
}

const TransportSlices& TransportLoss::slices() const {
    std::call_once(slices_->once, [&] { slices_->slices = std::make_unique<TransportSlices>(t_); });
    return *slices_->slices;
}

LossParts TransportLoss::evaluateUnbiased(std::span<const double> E, std::span<double> grad) const {
    if (const TransportGram* g = evaluationGram()) return evaluateGram(*g, E, {}, false, grad);
    const Products product{t_, productSlices()};
    product.luminanceHalves(E, y_, yb_);
    shard_.gatherImage(y_, t_.width);
    shard_.gatherImage(yb_, t_.width);
    if (grad.empty()) return unb_->evaluate(y_, yb_, E);
    std::vector<double> dLdE(dimension_);
    LossParts parts = unb_->evaluate(y_, yb_, E, dLdY_, dLdYb_, dLdE);
    product.transposeHalves(dLdY_, dLdYb_, grad);
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
    const Products product{t_, productSlices()};
    product.luminance(E, y_);
    shard_.gatherImage(y_, t_.width);
    if (grad.empty()) return obj_->evaluate(y_, E);
    if (grad.size() != dimension_)
        throw std::invalid_argument("TransportLoss: gradient has the wrong size");
    std::vector<double> dLdE(dimension_);
    LossParts parts = obj_->evaluate(y_, E, dLdY_, dLdE);
    product.transpose(dLdY_, grad);
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
    const TransportSlices* blk = productSlices();
    auto applyRows = [&](double* Y, size_t r0, size_t r1) {
        if (blk)
            blk->applyLuminanceRows(E.data(), rgbE, Y, r0, r1);
        else
            t_.applyLuminanceRows(E.data(), rgbE, Y, r0, r1);
    };
    // Tᵀ·g of a band into a chunk's sums: the slices' per-lane sums (added into the chunk's
    // partial at its end), or T's own product straight into the partial.
    const size_t lanes = blk ? TransportSlices::kLanes : 1;
    auto transposeRows = [&](const double* g, double* out, size_t r0, size_t r1) {
        if (blk)
            blk->accumulateTransposeLanes(g, rgbE, out, r0, r1);
        else
            t_.accumulateTransposeRows(g, rgbE, out, r0, r1);
    };
    // At most 16 chunks (each keeps its own Tᵀ·s), of at least 16 rows and ~16 k pixels.
    const int chunkRows = std::max({16, (H + 15) / 16, (16384 + W - 1) / W}), band = 2;
    const int nChunks = (H + chunkRows - 1) / chunkRows;
    // Per chunk: Tᵀ·s (n), then Tᵀ·Y for the image regulariser (n, when it is on).
    const size_t per = regScale != 0 ? 2 * n : n;
    partial_.resize(static_cast<size_t>(nChunks) * per);
    struct ChunkSums {
        double G = 0, sumY2 = 0;
    };
    std::vector<ChunkSums> sums(static_cast<size_t>(nChunks));

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
            applyRows(rowOf(yl, computed), computed * w, upto * w);
            computed = upto;
        };
        if (a > 0) {  // the vertical pairs (a-1, a) that the previous chunk owns touch row a
            ensureY(a + 1);
            obj_->accumulateSignsRows(yl.data(), sl.data(), a - 1, a, lo);  // G: the previous's
        }
        double* gsk = partial_.data() + static_cast<size_t>(k) * per;
        std::fill(gsk, gsk + per, 0.0);
        thread_local std::vector<double> laneSums;
        double* sums8 = gsk;  // where the bands' Tᵀ·s (then Tᵀ·Y) go
        if (blk) {
            laneSums.assign(per * lanes, 0.0);
            sums8 = laneSums.data();
        }
        double* gyk = regScale != 0 ? sums8 + n * lanes : nullptr;
        ChunkSums cs;
        for (int y0 = a; y0 < b; y0 += band) {
            const int y1 = std::min(y0 + band, b);
            ensureY(std::min(y1 + 1, hi));
            cs.G += obj_->accumulateSignsRows(yl.data(), sl.data(), y0, y1, lo);
            // Rows [y0, y1) now have their final s; their T rows were just read for Y.
            transposeRows(rowOf(sl, y0), sums8, y0 * w, y1 * w);
            if (gyk) transposeRows(rowOf(yl, y0), gyk, y0 * w, y1 * w);
            cs.sumY2 += sumOfSquares(rowOf(yl, y0), static_cast<size_t>(y1 - y0) * w);
            std::copy(rowOf(yl, y0), rowOf(yl, y1), y_.data() + y0 * w);
        }
        if (blk) TransportSlices::addLanes(sums8, gsk, per);
        sums[static_cast<size_t>(k)] = cs;
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

    // The loss from the chunks' sums, in chunk order; the objective assembles it.
    ChunkSums total;
    for (const ChunkSums& cs : sums) {
        total.G += cs.G;
        total.sumY2 += cs.sumY2;
    }
    dLdE_.resize(n);
    // A non-finite Y or E makes Σ Y² or Σ E² non-finite (so may an overflow): then the
    // objective's own checks run, and throw naming the value.
    if (!std::isfinite(total.sumY2) || !std::isfinite(sumOfSquares(E.data(), E.size())))
        obj_->evaluate(y_, E, {}, dLdE_);
    LossParts parts = obj_->fromSums(total.G, total.sumY2, E, dLdE_);
    const double scale = obj_->lGradScale(parts.G);
    for (size_t i = 0; i < n; ++i) {
        double s = 0, yy = 0;
        for (int k = 0; k < nChunks; ++k) {
            const double* p = partial_.data() + static_cast<size_t>(k) * per;
            s += p[i];
            if (regScale != 0) yy += p[n + i];
        }
        grad[i] = scale * s + regScale * yy + dLdE_[i];
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
    if (unb_) {
        // Auto: from the first evaluation on when the build pays (a lamp fit evaluates many
        // short-lived copies of this loss, which share one Gram; counting each copy's
        // evaluations would leave most of them on the columns).
        const bool useGram = gramEligible() && (layout_ == TransportLayout::Gram ||
                                                (layout_ == TransportLayout::Auto && gramPays()));
        if (useGram) {
            const TransportGram& g = gram();
            if (!grad.empty()) std::fill(grad.begin(), grad.end(), 0.0);
            return evaluateGram(g, E, active, true, grad);
        }
    }
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

HalfImages TransportLoss::halfImages(std::span<const double> E) const {
    if (t_.planes != 2) throw std::invalid_argument("TransportLoss::halfImages: T has no halves");
    if (E.size() != dimension_) throw std::invalid_argument("TransportLoss: E has the wrong size");
    HalfImages h{std::vector<double>(t_.rows()), std::vector<double>(t_.rows())};
    t_.applyLuminanceHalves(E, h.a, h.b);
    shard_.gatherImage(h.a, t_.width);
    shard_.gatherImage(h.b, t_.width);
    return h;
}

LossParts TransportLoss::evaluateImages(const HalfImages& images, std::span<const double> E) const {
    if (images.a.size() != images.b.size())
        throw std::invalid_argument("TransportLoss::evaluateImages: halves of different sizes");
    if (unb_) return unb_->evaluate(images.a, images.b, E);
    std::vector<double> y(images.a.size());
    for (size_t p = 0; p < y.size(); ++p) y[p] = 0.5 * (images.a[p] + images.b[p]);
    return obj_->evaluate(y, E);
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
    if (offersHessian())
        p.hessianProduct = [this](std::span<const double> x, std::span<const double> v,
                                  std::span<double> hv) { hessianProduct(x, v, hv); };
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
