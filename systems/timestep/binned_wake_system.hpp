#pragma once
/// @file binned_wake_system.hpp
/// @brief Binned stepping, after the collision net: a particle the net put back on a wall has a
/// state that no longer follows from its last evaluation. The corrected position, velocity and
/// density become its base state at the step's end (so the extrapolation of He Alg. 2 lines
/// 19-21 continues from them), and its step is cut to end at the next due time
/// (BinTimeline::next), where it is evaluated (the rule `individual` applies through
/// comp::wake). Its bin becomes the largest that time allows.
/// Cost: O(particles corrected this step).
#include "engine/graph/system.hpp"

namespace sph {

class BinnedWakeSystem final : public System {
public:
    std::string name() const override { return "binned_wake"; }
    Access access() const override;
    void run(Context& ctx) override;
};

}  // namespace sph
