// Emitters (scene `emitters`, engine/scene.hpp EmitterDesc): a disc of candidate positions on
// a square lattice of spacing r0 = 2 r, normal to the emission velocity. Each step an emitter
// owes rate x dt more particles; candidates are taken in a fixed order while the debt is at
// least one particle and the candidate is at least 0.95 r0 from every fluid and boundary
// particle (so a new particle is never inside another or inside a boundary, and a new layer
// waits until the previous one has moved on by about r0).
#include "systems/emit/emitter_system.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access EmitterSystem::access() const {
    return {{res::dt, res::boundary(comp::position.name), res::boundary_grid},
            {res::fluid(comp::position.name), res::fluid(comp::velocity.name), res::fluid(comp::id.name), res::fluid_count}};
}

void EmitterSystem::run(World& w) {
    const auto& emitters = w.scene.emitters;
    const double t = w.step.t, dt = w.step.dt;
    const Real r0 = w.physics.spacing, min_d2 = Real(0.95 * 0.95) * r0 * r0;
    const auto xb = w.boundary.store.get(comp::position);
    // `rate` and `max_particles` are per scale 1: `scale` multiplies the particle count, so it
    // multiplies both (the same volume of fluid flows in).
    const double scale = w.scene.simulation.scale;
    for (std::size_t e = 0; e < emitters.size(); ++e) {
        EmitterDesc em = emitters[e];
        em.rate *= scale;
        if (em.max_particles != std::numeric_limits<std::uint64_t>::max())
            em.max_particles = std::max<std::uint64_t>(1, std::uint64_t(std::llround(double(em.max_particles) * scale)));
        if (t + dt <= em.start || t >= em.end || w.emitters.emitted[e] >= em.max_particles) continue;
        const double active = std::min(t + dt, em.end) - std::max(t, em.start);
        w.emitters.budget[e] = std::min(w.emitters.budget[e] + em.rate * active, 1e7);
        if (w.emitters.budget[e] < 1.0) continue;
        // Fluid particles that could be near the disc (one O(N) pass).
        const auto x = w.fluid.store.get(comp::position);
        const Real reach = Real(em.radius) + r0;
        const Vec3 c = em.position.cast<Real>();
        std::vector<Vec3> near;
        for (const Vec3& p : x)
            if ((p - c).squaredNorm() < reach * reach) near.push_back(p);
        std::vector<Vec3> add;
        for (const Vec3d& candidate : emitter_disc(em, double(r0))) {
            if (w.emitters.budget[e] < 1.0 || w.emitters.emitted[e] + add.size() >= em.max_particles) break;
            const Vec3 p = candidate.cast<Real>();
            bool clear = true;
            for (const Vec3& q : near)
                if ((p - q).squaredNorm() < min_d2) clear = false;
            for (const Vec3& q : add)
                if ((p - q).squaredNorm() < min_d2) clear = false;
            if (clear && xb.size() > 0)
                w.boundary_grid.for_each_candidate(p, [&](Index, const Vec3& q) {
                    if ((p - q).squaredNorm() < min_d2) clear = false;
                });
            if (!clear) continue;
            add.push_back(p);
            w.emitters.budget[e] -= 1.0;
        }
        if (add.empty()) continue;
        const std::size_t n0 = w.fluid.size();
        w.fluid.store.resize(n0 + add.size());
        auto xs = w.fluid.store.get(comp::position);
        auto vs = w.fluid.store.get(comp::velocity);
        auto id = w.fluid.store.get(comp::id);
        for (std::size_t a = 0; a < add.size(); ++a) {
            xs[n0 + a] = add[a];
            vs[n0 + a] = em.velocity.cast<Real>();
            id[n0 + a] = w.emitters.next_id++;
        }
        w.emitters.emitted[e] += add.size();
    }
}

}  // namespace sph
