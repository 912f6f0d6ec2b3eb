// Binned stepping: the rows within reach of a moving body, made due (binned_body_system.hpp).
#include "systems/active/binned_body_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/active/select_active_system.hpp"
#include "systems/integrate/drift.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

Access BinnedBodySystem::access() const {
    return Access()
        .read(res::moving_bodies, res::bin_timeline, res::drift_bound, fluid(comp::dt), fluid(comp::position_last),
              fluid(comp::velocity_last), fluid(comp::acceleration), fluid(comp::t_last))
        .write(fluid(comp::bin), fluid(comp::ti_end), fluid(comp::active), res::due_buckets, res::active_set,
               counter::active, counter::body_candidates);
}

void BinnedBodySystem::register_components(World& w) {
    w.resources.add<DriftBound>(res::drift_bound.name, Lifetime::Scratch);
}

void BinnedBodySystem::make_list(Context& ctx, const std::vector<MovingBody>& bodies, double reach) {
    const auto x0 = ctx.read(fluid(comp::position_last));
    const auto v0 = ctx.read(fluid(comp::velocity_last));
    const auto a = ctx.read(fluid(comp::acceleration));
    const auto t_last = ctx.read(fluid(comp::t_last));
    const Tick now = ctx.clock().t_ticks;
    const Real h = ctx.physics().h;
    std::vector<MovingBody> wide = bodies;
    for (MovingBody& b : wide) {  // at speed 0 near_moving_body's reach is h: the box widened by the rest
        b.speed = 0;
        b.bounds.min.array() -= reach - double(h);
        b.bounds.max.array() += reach - double(h);
    }
    tbb::enumerable_thread_specific<std::vector<Index>> found;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x0.size(), 4096), [&](const auto& r) {
        auto& out = found.local();
        for (std::size_t i = r.begin(); i < r.end(); ++i)
            if (near_moving_body(wide, position_from_base(now, t_last[i], x0[i], v0[i], a[i]), 0, h)) out.push_back(Index(i));
    });
    m_list.clear();
    for (auto& v : found) m_list.insert(m_list.end(), v.begin(), v.end());
    std::sort(m_list.begin(), m_list.end());
    m_boxes.clear();
    for (const MovingBody& b : bodies) m_boxes.push_back(b.bounds);
    m_layout = ctx.layout(SetId::Fluid);
    m_moved = 0;
    ++m_lists_made;
}

void BinnedBodySystem::run(Context& ctx) {
    const auto& bodies = ctx.read(res::moving_bodies);
    const BinTimeline& tl = ctx.read(res::bin_timeline);
    const Tick now = ctx.clock().t_ticks;
    const double h = ctx.physics().h;
    // d_f over (last step, now]: DriftBound holds since its reset, which is at most the last
    // step's start, and net_shift is the net's largest jump in the last step (infinite after a
    // hit on a moving body). The float rounding of two drifted positions, a few units in the
    // last place of the domain's largest coordinate, is added per step.
    const DriftBound& bound = ctx.read(res::drift_bound);
    const Aabb& domain = ctx.domain();
    const double extent = std::max(domain.min.cwiseAbs().maxCoeff(), domain.max.cwiseAbs().maxCoeff());
    if (bound.membership != ctx.membership(SetId::Fluid))
        m_moved = std::numeric_limits<double>::infinity();
    else
        m_moved += bound.speed(m_lambda_v, m_lambda_f, h) * to_seconds(now - m_last) * 1.001 + bound.net_shift_static +
                   8 * double(std::numeric_limits<Real>::epsilon()) * extent;
    m_last = now;
    ctx.write(counter::body_candidates) = 0;
    // Only at a due time (BinnedSelectSystem set now = next there; BinnedStepSystem plans next
    // after now, so they differ on every other step).
    if (bodies.empty() || tl.now != tl.next || now != ticks_of(tl, tl.now)) return;
    double speed = 0;
    for (const MovingBody& b : bodies) speed = std::max(speed, b.speed);
    const double reach = h + speed * m_dt_max * 1.001;  // every row's reach now (dt_i <= dt_max)
    // How far the boxes moved since the list was made (each side of each box).
    double boxes_moved = m_boxes.size() == bodies.size() ? 0 : std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < m_boxes.size() && k < bodies.size(); ++k)
        boxes_moved = std::max({boxes_moved, (bodies[k].bounds.min - m_boxes[k].min).cwiseAbs().maxCoeff(),
                                (bodies[k].bounds.max - m_boxes[k].max).cwiseAbs().maxCoeff()});
    const double margin = kMargin * h;
    if (ctx.layout(SetId::Fluid) != m_layout || !(m_moved + boxes_moved < margin)) make_list(ctx, bodies, reach + margin);
    const auto x0 = ctx.read(fluid(comp::position_last));
    const auto v0 = ctx.read(fluid(comp::velocity_last));
    const auto a = ctx.read(fluid(comp::acceleration));
    const auto t_last = ctx.read(fluid(comp::t_last));
    const auto dt = ctx.read(fluid(comp::dt));
    auto bin = ctx.write(fluid(comp::bin));
    auto ti_end = ctx.write(fluid(comp::ti_end));
    auto active = ctx.write(fluid(comp::active));
    DueBuckets& buckets = ctx.write(res::due_buckets);
    auto& set = ctx.write(res::active_set);
    const int top = BinTimeline::largest_aligned_bin(tl.now, tl.max_bin);
    m_added.clear();
    for (const Index i : m_list) {
        if (active[i]) continue;  // due already
        if (!near_moving_body(bodies, position_from_base(now, t_last[i], x0[i], v0[i], a[i]), dt[i], Real(h))) continue;
        ti_end[i] = tl.now;
        bin[i] = std::uint8_t(std::min<int>(bin[i], top));
        buckets.bin_lo = std::min<int>(buckets.bin_lo, bin[i]);
        active[i] = 1;
        m_added.push_back(i);
    }
    ctx.write(counter::body_candidates) = m_list.size();
    if (!m_added.empty()) {
        // The set stays ascending (BinnedSelectSystem's order), each row once.
        const std::size_t mid = set.size();
        set.insert(set.end(), m_added.begin(), m_added.end());
        if (set.size() == ti_end.size())
            std::iota(set.begin(), set.end(), Index(0));
        else
            std::inplace_merge(set.begin(), set.begin() + std::ptrdiff_t(mid), set.end());
    }
    ctx.write(counter::active) = set.size();
}

}  // namespace sph
