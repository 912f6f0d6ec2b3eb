// Emitters (scene `emitters`, engine/scene.hpp EmitterDesc): a disc of candidate positions on
// a square lattice of spacing r0 = 2 r, normal to the emission velocity. Each step an emitter
// owes rate x dt more particles; candidates are taken in a fixed order while the debt is at
// least one particle and the candidate is at least 0.95 r0 from every fluid and boundary
// particle (so a new particle is never inside another or inside a boundary, and a new layer
// waits until the previous one has moved on by about r0).
#include "systems/emit/emitter_system.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <limits>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

void EmitterState::save(std::string& out) const {
    const std::uint64_t n = budget.size();
    out.append(reinterpret_cast<const char*>(&n), 8);
    out.append(reinterpret_cast<const char*>(budget.data()), n * 8);
    out.append(reinterpret_cast<const char*>(emitted.data()), n * 8);
    out.append(reinterpret_cast<const char*>(&next_id), 4);
}

void EmitterState::load(std::string_view in) {
    std::uint64_t n = 0;
    if (in.size() >= 8) std::memcpy(&n, in.data(), 8);
    if (in.size() < 8 || n != budget.size() || in.size() != 8 + 16 * n + 4)
        throw std::runtime_error("does not hold the state of " + std::to_string(budget.size()) + " emitters");
    std::memcpy(budget.data(), in.data() + 8, n * 8);
    std::memcpy(emitted.data(), in.data() + 8 + 8 * n, n * 8);
    std::memcpy(&next_id, in.data() + 8 + 16 * n, 4);
}

Access EmitterSystem::access() const {
    return Access()
        .read(res::dt, boundary(comp::position), res::boundary_grid)
        .write(fluid(comp::position), fluid(comp::velocity), fluid(comp::id), res::emitter_state)
        .resizes(SetId::Fluid);
}

void EmitterSystem::register_components(World& w) {
    EmitterState& st = w.resources.add<EmitterState>(res::emitter_state.name, Lifetime::Kept);
    st.budget.assign(m_emitters.size(), 0.0);
    st.emitted.assign(m_emitters.size(), 0);
    st.next_id = std::uint32_t(w.fluid.size());
}

void EmitterSystem::run(Context& ctx) {
    const auto& emitters = m_emitters;
    EmitterState& state = ctx.write(res::emitter_state);
    const double t = ctx.clock().t, dt = ctx.read(res::dt).dt;
    const UniformGrid& boundary_grid = ctx.read(res::boundary_grid);
    const Real r0 = ctx.physics().spacing, min_d2 = Real(0.95 * 0.95) * r0 * r0;
    const auto xb = ctx.read(boundary(comp::position));
    // `rate` and `max_particles` are per scale 1: `scale` multiplies the particle count, so it
    // multiplies both (the same volume of fluid flows in).
    const double scale = m_scale;
    for (std::size_t e = 0; e < emitters.size(); ++e) {
        EmitterDesc em = emitters[e];
        em.rate *= scale;
        if (em.max_particles != std::numeric_limits<std::uint64_t>::max())
            em.max_particles = std::max<std::uint64_t>(1, std::uint64_t(std::llround(double(em.max_particles) * scale)));
        if (t + dt <= em.start || t >= em.end || state.emitted[e] >= em.max_particles) continue;
        const double active = std::min(t + dt, em.end) - std::max(t, em.start);
        state.budget[e] = std::min(state.budget[e] + em.rate * active, 1e7);
        if (state.budget[e] < 1.0) continue;
        // Fluid particles that could be near the disc (one O(N) pass).
        const auto x = ctx.read(fluid(comp::position));
        const Real reach = Real(em.radius) + r0;
        const Vec3 c = em.position.cast<Real>();
        std::vector<Vec3> near;
        for (const Vec3& p : x)
            if ((p - c).squaredNorm() < reach * reach) near.push_back(p);
        std::vector<Vec3> add;
        for (const Vec3d& candidate : emitter_disc(em, double(r0))) {
            if (state.budget[e] < 1.0 || state.emitted[e] + add.size() >= em.max_particles) break;
            const Vec3 p = candidate.cast<Real>();
            bool clear = true;
            for (const Vec3& q : near)
                if ((p - q).squaredNorm() < min_d2) clear = false;
            for (const Vec3& q : add)
                if ((p - q).squaredNorm() < min_d2) clear = false;
            if (clear && xb.size() > 0)
                boundary_grid.for_each_candidate(p, xb, [&](Index, const Vec3& q) {
                    if ((p - q).squaredNorm() < min_d2) clear = false;
                });
            if (!clear) continue;
            add.push_back(p);
            state.budget[e] -= 1.0;
        }
        if (add.empty()) continue;
        const std::size_t n0 = ctx.size(SetId::Fluid);
        ctx.resize(SetId::Fluid, n0 + add.size());
        auto xs = ctx.write(fluid(comp::position));
        auto vs = ctx.write(fluid(comp::velocity));
        auto id = ctx.write(fluid(comp::id));
        for (std::size_t a = 0; a < add.size(); ++a) {
            xs[n0 + a] = add[a];
            vs[n0 + a] = em.velocity.cast<Real>();
            id[n0 + a] = state.next_id++;
        }
        state.emitted[e] += add.size();
    }
}

}  // namespace sph
