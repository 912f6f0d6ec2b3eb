#pragma once
/// @file dt_propagation_system.hpp
/// @brief Individual time stepping, He et al. Alg. 2 line 16 (Delta t_i = min over the
/// neighbours j of Delta t_j^raw, i itself included); line 17 is individual_dt_system.hpp.
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief He Alg. 2 line 16, run only where a Delta t^raw changed: for every active particle
/// and every inactive neighbour of one (the halo). Each gets the minimum over its own list
/// (fresh for the active, the last one for the halo) and itself; then every active particle
/// pushes its Delta t^raw onto the particles in its fresh list (an atomic minimum), so a
/// sleeping particle that an active one has just come near learns the short step at once.
class DtPropagationSystem final : public System {
public:
    std::string name() const override { return "dt_propagation"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
};


}  // namespace sph
