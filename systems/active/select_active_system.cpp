// He et al. Alg. 2 line 2: select active (t_last + Delta t_i <= t_sim, in exact ticks).
#include "systems/active/select_active_system.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access SelectActiveSystem::access() const {
    return {{res::fluid(comp::t_last.name), res::fluid(comp::dt.name), res::fluid(comp::position.name),
             res::moving_bodies},
            {res::fluid(comp::active.name), res::fluid(comp::wake.name), res::active_set}};
}

void SelectActiveSystem::register_components(World& w) {
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::active);
    w.fluid.store.add(comp::wake);
}

void SelectActiveSystem::run(World& w) {
    const auto t_last = w.fluid.store.get(comp::t_last);
    const auto dt = w.fluid.store.get(comp::dt);
    auto active = w.fluid.store.get(comp::active);
    auto wake = w.fluid.store.get(comp::wake);
    const auto x = w.fluid.store.get(comp::position);
    const Tick now = w.step.t_ticks;
    // The deadline rule (scene key simulation.stepping.activation, default): evaluate a particle
    // at the last step that starts before its deadline t_last + Delta t_i, predicting this step's
    // length by the last stable Delta t_sim (IndividualGlobalDtSystem then keeps the step from
    // carrying anyone past a deadline). He's rule as written (`paper`) evaluates at the first
    // step that starts at or after the deadline: ahead = one tick.
    const Tick ahead = w.scene.simulation.stepping.activation == Activation::Deadline
                           ? std::max<Tick>(1, to_ticks(w.step.dt_stable))
                           : Tick(1);
    const std::size_t n = t_last.size();
    const Real h = w.physics.h;
    const auto& bodies = w.moving_bodies;
    // Moving boundaries (our rule, not in He et al.): a particle is active while it lies within
    // h + speed * Delta t_i of a moving body's bounding box, i.e. wherever the body could come
    // within the kernel's reach before the particle's next evaluation. It therefore never
    // skips a contact, and the body's velocity enters its forces at every step of the contact.
    auto near_moving_body = [&](std::size_t i) {
        for (const MovingBody& b : bodies) {
            const Real reach = h + Real(b.speed * dt[i]);
            const Vec3 lo = b.bounds.min.cast<Real>().array() - reach, hi = b.bounds.max.cast<Real>().array() + reach;
            if ((x[i].array() >= lo.array()).all() && (x[i].array() <= hi.array()).all()) return true;
        }
        return false;
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            // He Alg. 2 line 2. `paper`: deadline <= now, the tie counted as active (the paper
            // writes "<"; with "<" a particle whose Delta t_i equals Delta t_sim would wait two
            // steps). `deadline`: deadline < now + ahead.
            active[i] = (t_last[i] + to_ticks(dt[i]) < now + ahead) || wake[i] || (!bodies.empty() && near_moving_body(i));
            wake[i] = 0;
        }
    });
    w.active_set = collect_indices(n, [&](std::size_t i) { return active[i] != 0; });
    w.step.active = w.active_set.size();
}

Access HaloSystem::access() const {
    Access a{{res::active_set, res::fluid_neighbours, res::fluid(comp::active.name)}, {res::halo_set}};
    if (m_with_boundary) a.reads.push_back(res::boundary_neighbours);
    return a;
}

void HaloSystem::register_components(World& w) { w.fluid.store.add(comp::active); }

void HaloSystem::run(World& w) {
    const auto active = w.fluid.store.get(comp::active);
    const auto& set = w.active_set;
    // A per-particle claim flag keeps each halo particle once; flags are cleared afterwards
    // by walking the halo itself, so the cost stays proportional to the active set.
    m_claim.resize(active.size());
    if (set.size() == active.size()) {  // everyone active: no halo (global-equivalent steps)
        w.halo_set.clear();
        std::uint64_t b = 0;
        if (m_with_boundary)
            for (auto c : w.boundary_neighbours.count) b += c;
        w.step.boundary_contributions = b;
        return;
    }
    tbb::enumerable_thread_specific<std::vector<Index>> local;
    tbb::enumerable_thread_specific<std::uint64_t> boundary_entries(0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), 256), [&](const auto& r) {
        auto& out = local.local();
        auto& bcount = boundary_entries.local();
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = set[k];
            for (Index j : w.fluid_neighbours.of(i)) {
                if (active[j]) continue;
                // A plain load first: most halo particles neighbour several active ones, and
                // the locked exchange (the cost of this system) is only paid on a first claim.
                std::atomic_ref<std::uint8_t> claim(m_claim[j]);
                if (claim.load(std::memory_order_relaxed) != 0) continue;
                if (claim.exchange(1, std::memory_order_relaxed) == 0) out.push_back(j);
            }
            if (m_with_boundary) bcount += w.boundary_neighbours.count[i];
        }
    });
    w.halo_set.clear();
    for (auto& v : local) w.halo_set.insert(w.halo_set.end(), v.begin(), v.end());
    // No sort: the order varies with the thread schedule, but nothing depends on it (the
    // propagation writes each halo particle's own minimum, then takes atomic minima).
    for (Index j : w.halo_set) m_claim[j] = 0;
    std::uint64_t b = 0;
    for (auto c : boundary_entries) b += c;
    w.step.boundary_contributions = b;
}

}  // namespace sph
