#include "optimize/PaperSetup.h"

#include <sstream>

namespace sl {

std::string paperSetupText() {
    const PaperSetup& p = kPaperSetup;
    std::ostringstream s;
    s << "eq. 2, lambda " << p.lambda << " on "
      << (p.reg == RegTarget::EnvMap ? "mean(E^2)" : "sum Y^2/(W H)") << ", Adam lr "
      << p.learningRate << " x " << p.steps << " from E0 = " << p.start;
    return s.str();
}

}  // namespace sl
