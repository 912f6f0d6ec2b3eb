// Ihmsen et al. 2010 sec. 3.2, eq. 9-12: direct forcing against the boundary particles.
#include "systems/pcisph/direct_forcing.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

void direct_forcing(Context& ctx, bool predicted, bool moving, double friction_eps) {
    auto x = predicted ? ctx.write(fluid(comp::predicted_position)) : ctx.write(fluid(comp::position));
    const std::span<Vec3> v = predicted ? std::span<Vec3>{} : ctx.write(fluid(comp::velocity));
    const auto xb = ctx.read(boundary(comp::position));
    const auto nb = ctx.read(boundary(comp::normal));
    const std::span<const Vec3> vb = (!predicted && moving && ctx.has(SetId::Boundary, comp::velocity.name))
                                         ? ctx.read(boundary(comp::velocity))
                                         : std::span<const Vec3>{};
    const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
    // r0: the rest distance, which Ihmsen sec. 3.2 takes equal to the boundary particles' spacing
    // ("r0 = 0.5 h" with h = 2 spacings there); the boundary is sampled at the fluid spacing 2 r
    // (world_init.cpp), so r0 is that spacing at any fluid.support (h / 2 only at the default 2).
    const Real r0 = ctx.physics().spacing;
    const Real friction = Real(friction_eps);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            DirectForcing df{r0};
            for (Index b : lists.of(Index(i)))
                df.add(x[i], xb[b], nb[b], vb.empty() ? Vec3::Zero() : vb[b]);
            if (!df.hit()) continue;
            x[i] = df.corrected(x[i]);                          // eq. 11
            if (!predicted) v[i] = df.velocity(v[i], friction);  // eq. 12
        }
    });
}

}  // namespace sph
