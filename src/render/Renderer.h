// Renderer: any renderer as a black box for ONE fixed scene and camera: an env map in (on the
// scene's EnvMapBasis grid, scene/EnvMapBasis.h), a linear RGB float image out (the camera's
// width × height, 3 channels, top row first, background 0). Two kinds:
//   * BuiltinRenderer (here): our path tracer through render() (render/Render.h);
//   * external processes (POV-Ray, or any command line): app/host/ExternalRenderer.h, because
//     running a process and writing its files belongs to io/ and app/.
// The black-box gradients (optimize/BlackBox.h) and the basis-render T (app/host/ExternalRenderer.h)
// use only this interface.
//
// SEEDS: render(env, seed) draws its samples from `seed` when the renderer has one (seeded());
// a renderer without (POV-Ray here: deterministic supersampling) renders the same samples for
// every seed, so its renders are common random numbers by construction.
#pragma once

#include <cstdint>
#include <string>

#include "core/Image.h"
#include "render/PathTracer.h"
#include "scene/EnvMap.h"

namespace sl {

struct Scene;

class Renderer {
  public:
    virtual ~Renderer() = default;
    /// Short name for messages and summaries ("builtin", "povray", "command").
    virtual std::string name() const = 0;
    /// Linear RGB image (width() × height(), 3 channels) of the scene under `env`.
    /// threads: worker threads for this one render (0: all cores). Throws on failure, with a
    /// message that says what failed and how to fix it.
    virtual Image render(const EnvMap& env, uint64_t seed, int threads) const = 0;
    /// Whether `seed` changes the samples.
    virtual bool seeded() const = 0;
    virtual int width() const = 0;
    virtual int height() const = 0;
};

/// Our path tracer: render(scene, env, options with `seed` and `threads`).
class BuiltinRenderer final : public Renderer {
  public:
    /// Keeps a reference to `scene`, which must outlive the renderer.
    BuiltinRenderer(const Scene& scene, RenderOptions options);
    std::string name() const override { return "builtin"; }
    Image render(const EnvMap& env, uint64_t seed, int threads) const override;
    bool seeded() const override { return true; }
    int width() const override;
    int height() const override;
    const RenderOptions& options() const { return options_; }

  private:
    const Scene& scene_;
    RenderOptions options_;
};

/// Relative linearity error of `renderer` on two env maps: ‖r(E1 + E2) − r(E1) − r(E2)‖₂ /
/// ‖r(E1 + E2)‖₂ over the image's values, with the same seed in all three renders (0 when
/// the sum renders black). A linear renderer gives its output's rounding error.
double linearityError(const Renderer& renderer, const EnvMap& e1, const EnvMap& e2, uint64_t seed,
                      int threads = 0);

}  // namespace sl
