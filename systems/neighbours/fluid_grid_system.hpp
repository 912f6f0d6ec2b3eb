#pragma once
/// @file fluid_grid_system.hpp
/// @brief He et al. Alg. 1 line 3 / Alg. 2 line 4, first half: the fluid grid, rebuilt every step.
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Sorts the fluid particles into the uniform grid (cell size h).
class FluidGridSystem final : public System {
public:
    std::string name() const override { return "fluid_grid"; }
    Access access() const override;
    void run(Context& ctx) override;
};

}  // namespace sph
