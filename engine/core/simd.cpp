#include "engine/core/simd.hpp"

#include "engine/core/simd_targets.hpp"  // the same compiled targets as the dispatching files

#include <hwy/highway.h>

#include <cstdint>
#include <vector>

namespace sph {

std::string simd_target() {
#ifdef SPH_DOUBLE
    return "scalar";
#else
    // The target HWY_DYNAMIC_DISPATCH picks: the best of those compiled that the CPU supports.
    const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
    return targets.empty() ? "none" : hwy::TargetName(targets.front());
#endif
}

}  // namespace sph
