// TransportLoss: the objective as a function of the env map E through a transport matrix,
// with its exact gradient  dLoss/dE = Tᵀ·dLoss/dY + dReg/dE  (docs/DESIGN.md "The one idea").
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/Communicator.h"
#include "core/Problem.h"
#include "core/WildBootstrap.h"
#include "objective/HalfImageObjective.h"
#include "objective/Objective.h"
#include "transport/TransportColumns.h"
#include "transport/TransportGram.h"
#include "transport/TransportMatrix.h"
#include "transport/TransportSlices.h"

namespace sl {

class TransportLoss {
  public:
    /// rgb: E has 3 values per texel (needs an RGB T); otherwise one (gray).
    TransportLoss(const TransportMatrix& t, const ImageObjective& objective, bool rgb);
    /// An objective on the halves of T (t.planes must be 2; the unbiased or the defects one):
    /// Y_a = T_a·E, Y_b = T_b·E, gradient T_aᵀ·dL/dY_a + T_bᵀ·dL/dY_b + dL/dE.
    TransportLoss(const TransportMatrix& t, const HalfImageObjective& objective, bool rgb);

    size_t dimension() const { return dimension_; }
    /// Ranks that each hold one row shard of T (io/TransportFile.h SHARDS) as this loss's
    /// matrix, this one the rows of `shard`: every product gives this rank's rows; the image is
    /// put together over the ranks (RowShard::gatherImage) before the objective, and
    /// Tᵀ·dLoss/dY summed over them (Communicator::sum) before dLoss/dE is added once, so every
    /// rank gets the whole loss and gradient and the ranks must evaluate in step. One process
    /// (the default): T alone. The fused pass and evaluateOnColumns are single-process only
    /// (the first falls back to evaluate, the second refuses).
    void distribute(const RowShard& shard) { shard_ = shard; }
    bool distributed() const { return shard_.distributed(); }
    /// Loss parts at E; fills grad (size dimension()) when it is non-empty.
    LossParts evaluate(std::span<const double> E, std::span<double> grad) const;
    /// The same loss and gradient in one streaming pass over T: bands of rows compute Y, the
    /// signs dG/dY of the pairs they own (with one halo row each side), their share of G (and
    /// of Σ Y²) and accumulate Tᵀ·s while T's rows are still in cache; the global factor
    /// −S/G² is applied at the end. Chunks are fixed, so the result does not depend on the
    /// number of threads; it equals evaluate()'s to rounding (G is summed band by band).
    LossParts evaluateFused(std::span<const double> E, std::span<double> grad) const;

    /// The layout the products read (transport/TransportSlices.h): Auto (default), Slices (a
    /// TransportSlices copy of T, built once and shared by copies of this loss, so T must not
    /// change after it) or Csr (T's own arrays, nothing built). Each copy counts its own
    /// evaluations for Auto, so its results do not depend on what other copies do.
    void setLayout(TransportLayout layout) { layout_ = layout; }
    TransportLayout layout() const { return layout_; }
    /// The slices layout of T (built on first use).
    const TransportSlices& slices() const;
    /// Whether this loss can be evaluated through T's Gram matrices: an objective quadratic in
    /// the halves, a gray E, a sparse T, one process.
    bool gramEligible() const;
    /// Whether Auto builds the Gram matrices (when eligible): their build's multiply-adds
    /// (TransportGram::buildWork) at most kGramWorkPerNonZero per non-zero of T, and the
    /// matrices at most kGramMaxBytes. The bundled part at 256², 16 spp needs 113 per non-zero,
    /// a build of some tens of sparse evaluations (`bench transport`), which L-BFGS's ~180
    /// evaluations repay; its answer equals the products' to rounding.
    bool gramPays() const;
    static constexpr double kGramWorkPerNonZero = 256;
    /// Whether `evaluations` through the products have cost what the Gram's build will (when
    /// eligible and within kGramMaxBytes): buildWork <= kGramWorkPerEvaluation per non-zero of
    /// T per evaluation. Auto builds it then where gramPays() is false: a search that runs
    /// long (L-BFGS's 886 evaluations on a steep 512² part) pays at most twice what the best
    /// choice in hindsight would have.
    bool gramRepaid(int evaluations) const;
    /// One evaluation through the slices, in the build's multiply-adds per non-zero of T: at
    /// 2048², 156 ms of CPU over 31.6 M non-zeros against 13.2 s for a build of 3.33·10⁹
    /// (docs/BENCHMARKS.md, issue 32's 2048² ratios).
    static constexpr double kGramWorkPerEvaluation = 1.25;
    static constexpr size_t kGramMaxBytes = size_t{256} << 20;
    /// The Gram matrices of T for this loss's objective (built on first use; gramEligible()),
    /// shared with every other loss on the same T and pair mask alive in the process (a lamps
    /// run's E* search and its fit build them once).
    const TransportGram& gram() const;
    /// The identity of gram() for a store of it (io/GramFile.h): T's `fingerprint` (its
    /// provenance's: every input of T), T's shape, this loss's pair mask and whether it needs
    /// Q, and the build's revision, as 32 hex digits. Needs gramEligible().
    std::string gramKey(const std::string& fingerprint) const;
    /// Installs matrices built before on this loss's T and pair mask (a stored copy of gram(),
    /// bit for bit), shared as gram() is: this loss and every other on the same T and mask
    /// read them instead of building their own while one holds them. False (nothing installed)
    /// when this loss has its Gram already, is not eligible, or they do not fit (another
    /// texel count; Q missing where the objective needs it).
    bool adoptGram(std::shared_ptr<const TransportGram> gram) const;
    /// Whether this loss has its Gram matrices now: its own, or adopted from another loss on
    /// the same T and pair mask that holds them (then gram() costs nothing).
    bool shareHeldGram() const;
    /// The Gram matrices this loss built or adopted (null when none yet).
    std::shared_ptr<const TransportGram> gramIfBuilt() const;

    /// The Hessian of the loss at E times v into Hv (dimension() values each), exact, through
    /// T's Gram matrices (gramEligible(); built on first use, as gram()). With the loss
    /// L = ℓ(G) + dLdR·R + reg(E) (objective/HalfImageObjective.h fromForms, formCurvature),
    ///   ∇²L·v = 2ℓ'(G)·P·v + 4ℓ''(G)·(P·E)·((P·E)ᵀ·v) + 2·dLdR·Q·v + reg''·v:
    /// one product with P (and one with Q for the image's regulariser) a call. P·E and G are
    /// the last evaluation's when it was a whole gradient evaluation at this E (an optimizer's
    /// iterate), else one more product.
    void hessianProduct(std::span<const double> E, std::span<const double> v,
                        std::span<double> Hv) const;
    /// Whether problem() offers hessianProduct: gramEligible() and the matrices within
    /// kGramMaxBytes.
    bool offersHessian() const;

    /// The same loss for an E that is zero outside the texels `active` (a gray E), through
    /// `columns` (a TransportColumns of this loss's matrix): the products read only the active
    /// columns. grad (when non-empty) is exact on the active texels; on the others it holds
    /// only the objective's direct dLoss/dE (the regulariser), not Tᵀ·dLoss/dY. An objective
    /// quadratic in the halves reads the Gram's active rows and columns instead (layout Gram,
    /// or Auto when gramPays(), from the first evaluation).
    LossParts evaluateOnColumns(const TransportColumns& columns, std::span<const double> E,
                                std::span<const uint16_t> active, std::span<double> grad) const;

    /// The luminance image T·E.
    std::vector<double> image(std::span<const double> E) const;
    /// The half images Y_a = T_a·E, Y_b = T_b·E (T must have two planes), put together over
    /// the ranks: what a bootstrap of this loss perturbs (core/WildBootstrap.h).
    HalfImages halfImages(std::span<const double> E) const;
    /// The loss (no gradient) at given half images and E: the halves' objective on them, or the
    /// image objective on their mean; evaluate(E) is this at halfImages(E), to rounding.
    LossParts evaluateImages(const HalfImages& images, std::span<const double> E) const;

    /// The box-constrained problem for the optimizers. `last` (optional) receives the parts
    /// of every evaluation.
    Problem problem(LossParts* last = nullptr, bool fused = true) const;

    const TransportMatrix& matrix() const { return t_; }
    bool onHalves() const { return unb_ != nullptr; }

  private:
    const TransportMatrix& t_;
    const ImageObjective* obj_ = nullptr;
    const HalfImageObjective* unb_ = nullptr;
    size_t dimension_;
    mutable std::vector<double> y_, dLdY_, yb_, dLdYb_;
    mutable std::vector<double> partial_, dLdE_;  // the fused pass's per-chunk sums, dReg/dE
    TransportLayout layout_ = TransportLayout::Auto;
    mutable int evaluations_ = 0;  // for TransportLayout::Auto
    /// The slices an evaluation's products read, or nullptr for CSR (counts the evaluation).
    const TransportSlices* productSlices() const;
    /// T's products through the layout chosen for one evaluation (slices, or T's CSR arrays
    /// when null): the one place that dispatches on it.
    struct Products {
        const TransportMatrix& t;
        const TransportSlices* slices;
        void luminance(std::span<const double> E, std::span<double> y) const;
        void luminanceHalves(std::span<const double> E, std::span<double> ya,
                             std::span<double> yb) const;
        void transpose(std::span<const double> dy, std::span<double> g) const;
        void transposeHalves(std::span<const double> dya, std::span<const double> dyb,
                             std::span<double> g) const;
    };
    struct SlicesCache;
    std::shared_ptr<SlicesCache> slices_;
    struct GramCache;
    std::shared_ptr<GramCache> gram_;
    mutable std::vector<double> pe_, qe_;  // P·E, Q·E of a Gram evaluation
    mutable std::vector<double> peAt_;     // the E at which pe_ and gAt_ hold P·E and G (or empty)
    mutable double gAt_ = 0;
    mutable std::vector<double> hp_, hq_;  // P·v, Q·v of a Hessian product
    /// The Gram matrices an evaluation reads, or nullptr for the products (for Auto: from the
    /// kAutoSlicesAfter-th evaluation on, counted by productSlices(), or from the first when
    /// this loss has them already).
    const TransportGram* evaluationGram() const;
    void decideGram() const;  // gram_'s fits, work and pays, once
    LossParts evaluateGram(const TransportGram& g, std::span<const double> E,
                           std::span<const uint16_t> active, bool onActive,
                           std::span<double> grad) const;
    RowShard shard_;

    LossParts evaluateUnbiased(std::span<const double> E, std::span<double> grad) const;
};

/// A stochastic loss over K independent estimates of T (the same objective on each): every
/// evaluation WITH a gradient uses the next estimate in turn (k = n mod K), so a step-wise
/// optimizer (Adam) sees a fresh sample set every iteration, as the paper's loop that renders
/// anew each iteration. An evaluation WITHOUT a gradient returns the mean over all K, a stable
/// value for reports. With K = 1 it is the loss itself.
class CyclingLoss {
  public:
    explicit CyclingLoss(std::vector<const TransportLoss*> losses);
    size_t dimension() const { return losses_.front()->dimension(); }
    size_t count() const { return losses_.size(); }
    /// Loss parts; fills grad (and advances to the next estimate) when grad is non-empty.
    LossParts evaluate(std::span<const double> E, std::span<double> grad);
    Problem problem(LossParts* last = nullptr);
    /// The next gradient evaluation uses the first estimate again.
    void restart() { next_ = 0; }

  private:
    std::vector<const TransportLoss*> losses_;
    size_t next_ = 0;
};

}  // namespace sl
