// Ihmsen et al. 2010 Alg. 2 "world collision": eq. 9-12 on x(t + dt) and v(t + dt).
#include "systems/pcisph/world_collision_system.hpp"

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/direct_forcing.hpp"
#include "systems/pcisph/pcisph_components.hpp"

namespace sph {

void WorldCollisionSystem::register_components(World& w) { ensure_boundary_normals(w); }

Access WorldCollisionSystem::access() const {
    return Access()
        .read(res::boundary_neighbours, boundary(comp::position), boundary(comp::normal))
        .write(fluid(comp::position), fluid(comp::velocity))
        .read_if(m_moving, boundary(comp::velocity));
}

void WorldCollisionSystem::run(Context& ctx) { direct_forcing(ctx, false, m_moving, m_friction); }

}  // namespace sph
