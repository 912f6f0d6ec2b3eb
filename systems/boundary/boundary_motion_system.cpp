// Kinematic boundaries: x_b(t) = x0_b + d(t), v_b(t) = d'(t) for every particle b of a moving
// body (a rigid translation; Akinci et al. 2012 sec. 3 move boundary particles with their body).
#include "systems/boundary/boundary_motion_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <limits>

#include "engine/data/components.hpp"
#include "engine/data/motion.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access BoundaryMotionSystem::access() const {
    return Access()
        .read(boundary(comp::rest_position))
        .write(boundary(comp::position), boundary(comp::velocity), res::boundary_grid, res::moving_bodies);
}

void BoundaryMotionSystem::register_components(World& w) {
    // Normally registered and filled by initialise_world already (idempotent).
    w.boundary.store.add(comp::rest_position);
    w.boundary.store.add(comp::velocity);
}

void BoundaryMotionSystem::run(Context& ctx) {
    auto x = ctx.write(boundary(comp::position));
    auto vb = ctx.write(boundary(comp::velocity));
    const auto x0 = ctx.read(boundary(comp::rest_position));
    const double t = ctx.clock().t;
    for (MovingBody& body : ctx.write(res::moving_bodies)) {
        const Motion& motion = *m_boundaries.at(body.boundary).motion;
        const Vec3d d = displacement(motion, t);
        const Vec3 v = velocity(motion, t).cast<Real>();
        using Box = std::pair<Vec3d, Vec3d>;
        const Box empty{Vec3d::Constant(std::numeric_limits<double>::max()),
                        Vec3d::Constant(std::numeric_limits<double>::lowest())};
        const Box box = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(body.begin, body.end, 2048), empty,
            [&](const auto& r, Box b) {
                for (std::size_t i = r.begin(); i < r.end(); ++i) {
                    // In double from the rest position: no round-off accumulates over steps.
                    x[i] = (x0[i].cast<double>() + d).cast<Real>();
                    vb[i] = v;
                    b.first = b.first.cwiseMin(x[i].cast<double>());
                    b.second = b.second.cwiseMax(x[i].cast<double>());
                }
                return b;
            },
            [](const Box& a, const Box& b) { return Box{a.first.cwiseMin(b.first), a.second.cwiseMax(b.second)}; });
        body.bounds = Aabb{box.first, box.second};
        body.speed = speed_bound(motion, t);
    }
    // The grid indexes every boundary particle: rebuilt whole (O(N_b + cells)) on a step where a
    // body's particle crossed into another cell, else left as it is, which is what a build
    // would give (UniformGrid::in_built_cells).
    UniformGrid& grid = ctx.write(res::boundary_grid);
    bool same = true;
    for (const MovingBody& body : ctx.read(res::moving_bodies))
        same = same && grid.in_built_cells(x, body.begin, body.end);
    if (!same) grid.build(x);
}

}  // namespace sph
