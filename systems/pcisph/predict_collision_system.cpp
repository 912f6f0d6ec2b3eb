// Ihmsen et al. 2010 Alg. 2 "predict world collision": eq. 9-11 on the predicted positions x*.
#include "systems/pcisph/predict_collision_system.hpp"

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/direct_forcing.hpp"
#include "systems/pcisph/pcisph_components.hpp"

namespace sph {

void PredictCollisionSystem::register_components(World& w) { ensure_boundary_normals(w); }

Access PredictCollisionSystem::access() const {
    return Access()
        .read(res::boundary_neighbours, boundary(comp::position), boundary(comp::normal))
        .write(fluid(comp::predicted_position));
}

void PredictCollisionSystem::run(Context& ctx) { direct_forcing(ctx, true, m_moving, m_friction); }

}  // namespace sph
