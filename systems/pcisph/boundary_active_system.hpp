#pragma once
/// @file boundary_active_system.hpp
/// @brief Ihmsen et al. 2010 sec. 3.4: the active boundary particles and their fluid neighbours.
#include <string>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Sec. 3.4: only boundary particles near fluid are active. Inverts the fluid->boundary
/// lists into boundary->fluid rows over the active set (ascending, deterministic).
class BoundaryActiveSystem final : public System {
public:
    std::string name() const override { return "boundary_active"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    std::vector<Index> m_count;
};

}  // namespace sph
