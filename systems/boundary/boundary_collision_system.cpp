// Position projection onto the declared boundary surfaces and removal of the velocity
// component into the wall (cf. Ihmsen et al. 2010, eq. 9-12, with the analytic surface normal).
// A moving boundary is handled in its own frame: its surface is moved by d(t + dt) and the
// velocity relative to it, v - v_b, loses its component into the body.
#include "systems/boundary/boundary_collision_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <limits>

#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/motion.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/integrate/drift.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

Access BoundaryCollisionSystem::access() const {
    Access a = Access()
        .write(fluid(comp::position), fluid(comp::velocity), fluid(comp::wake), counter::collisions)
        .write_if(m_active_rows, res::collided, res::drift_bound)
        .read_if(m_active_rows, res::active_set)
        .read_if(m_moving || m_active_rows, res::dt)  // the body's position at the step's end
        // binned: the end state of an active row from its base (it is not advanced before)
        .read_if(m_active_rows, fluid(comp::position_last), fluid(comp::velocity_last), fluid(comp::acceleration),
                 fluid(comp::t_last))
        .read_if(m_count_droplets, res::fluid_neighbours)
        .write_if(m_count_droplets, counter::droplet_contacts);
    if (m_active_rows) a.rows(res::active_set);
    return a;
}

namespace {

// Returns true and corrects (x, v) if x lies beyond the surface of boundary b.
bool collide(const BoundaryDesc& b, Vec3& x, Vec3& v) {
    switch (b.shape) {
        case BoundaryShape::Container: {
            bool hit = false;
            for (int a = 0; a < 3; ++a) {
                const Real lo = Real(b.box.min[a]), hi = Real(b.box.max[a]);
                if (x[a] < lo) {
                    x[a] = lo;
                    v[a] = std::max(v[a], Real(0));
                    hit = true;
                } else if (x[a] > hi) {
                    x[a] = hi;
                    v[a] = std::min(v[a], Real(0));
                    hit = true;
                }
            }
            return hit;
        }
        case BoundaryShape::Box: {
            const Vec3 lo = b.box.min.cast<Real>(), hi = b.box.max.cast<Real>();
            if (!((x.array() > lo.array()).all() && (x.array() < hi.array()).all())) return false;
            // Inside the solid: leave through the nearest face.
            int axis = 0;
            bool to_max = false;
            Real best = std::numeric_limits<Real>::max();
            for (int a = 0; a < 3; ++a) {
                if (x[a] - lo[a] < best) best = x[a] - lo[a], axis = a, to_max = false;
                if (hi[a] - x[a] < best) best = hi[a] - x[a], axis = a, to_max = true;
            }
            x[axis] = to_max ? hi[axis] : lo[axis];
            v[axis] = to_max ? std::max(v[axis], Real(0)) : std::min(v[axis], Real(0));
            return true;
        }
        case BoundaryShape::Sphere: {
            const Vec3 c = b.center.cast<Real>();
            const Vec3 d = x - c;
            const Real r = d.norm(), R = Real(b.radius);
            if (r >= R) return false;
            const Vec3 n = r > Real(0) ? Vec3(d / r) : Vec3::UnitY();
            x = c + R * n;
            const Real vn = v.dot(n);
            if (vn < 0) v -= vn * n;
            return true;
        }
        case BoundaryShape::Cylinder: {  // solid: leave through the side or the nearer cap
            const Vec3 c = b.center.cast<Real>(), ax = b.axis.cast<Real>();
            const Vec3 d = x - c;
            const Real along = d.dot(ax), H = Real(b.height), R = Real(b.radius);
            const Vec3 radial = d - along * ax;
            const Real rr = radial.norm();
            if (along <= 0 || along >= H || rr >= R) return false;
            const Real to_side = R - rr, to_cap = std::min(along, H - along);
            Vec3 n;
            if (to_side < to_cap) {
                n = rr > Real(0) ? Vec3(radial / rr) : Vec3::UnitX();
                x += to_side * n;
            } else {
                n = along < H - along ? Vec3(-ax) : ax;
                x += to_cap * n;
            }
            const Real vn = v.dot(n);
            if (vn < 0) v -= vn * n;
            return true;
        }
        case BoundaryShape::Heightfield: {  // fluid above: y >= h(x, z), bilinear
            const auto& hs = b.heights;
            const int nz = int(hs.size()), nx = int(hs[0].size());
            const double fx = (double(x.x()) - b.box.min.x()) / (b.box.max.x() - b.box.min.x()) * (nx - 1);
            const double fz = (double(x.z()) - b.box.min.z()) / (b.box.max.z() - b.box.min.z()) * (nz - 1);
            if (fx < 0 || fz < 0 || fx > nx - 1 || fz > nz - 1) return false;
            const int i = std::min(int(fx), nx - 2), k = std::min(int(fz), nz - 2);
            const double tx = fx - i, tz = fz - k;
            const double y = (1 - tz) * ((1 - tx) * hs[k][i] + tx * hs[k][i + 1]) + tz * ((1 - tx) * hs[k + 1][i] + tx * hs[k + 1][i + 1]);
            if (double(x.y()) >= y) return false;
            x.y() = Real(y);
            v.y() = std::max(v.y(), Real(0));
            return true;
        }
        case BoundaryShape::Mesh:
            return false;  // no analytic surface: the particle boundary alone (docs/methods.md)
    }
    return false;
}

}  // namespace

void BoundaryCollisionSystem::register_components(World& w) {
    if (m_active_rows) w.resources.add<DriftBound>(res::drift_bound.name, Lifetime::Scratch);
}

void BoundaryCollisionSystem::run(Context& ctx) {
    auto x = ctx.write(fluid(comp::position));
    auto v = ctx.write(fluid(comp::velocity));
    // Each boundary where it is at the end of this step (t + dt), and its velocity then. A
    // static boundary is its declared self with zero velocity.
    std::vector<BoundaryDesc> boundaries = m_boundaries;
    std::vector<Vec3> body_velocity(boundaries.size(), Vec3::Zero());
    bool any_moving = false;
    if (m_moving) {
        const double t_end = to_seconds(ctx.clock().t_ticks + ctx.read(res::dt).dt_ticks);
        for (std::size_t j = 0; j < boundaries.size(); ++j) {
            if (!boundaries[j].motion) continue;
            boundaries[j] = translated(boundaries[j], displacement(*boundaries[j].motion, t_end));
            body_velocity[j] = velocity(*boundaries[j].motion, t_end).cast<Real>();
            any_moving = true;
        }
    }
    const std::span<std::uint8_t> wake =
        ctx.has(SetId::Fluid, comp::wake.name) ? ctx.write(fluid(comp::wake)) : std::span<std::uint8_t>{};
    tbb::enumerable_thread_specific<std::vector<Index>> hits;
    const std::vector<Index>* rows = m_active_rows ? &ctx.read(res::active_set) : nullptr;
    const NeighbourLists* lists = m_count_droplets ? &ctx.read(res::fluid_neighbours) : nullptr;
    struct Count {
        std::uint64_t hits = 0, droplets = 0;
        double shift = 0;  ///< binned: the longest jump the net gave a row no moving body netted
        bool moving = false;  ///< binned: a moving body netted a row
    };
    // Binned stepping: an active row holds its state at the step's start and its new base; its
    // state at the step's end is He Alg. 2 lines 19-21 from that base (written only if netted;
    // otherwise the next step's drift computes the same values).
    std::span<const Vec3> x0, v0, acc;
    std::span<const std::int64_t> t_last;
    Tick t_end = 0;
    if (m_active_rows) {
        x0 = ctx.read(fluid(comp::position_last));
        v0 = ctx.read(fluid(comp::velocity_last));
        acc = ctx.read(fluid(comp::acceleration));
        t_last = ctx.read(fluid(comp::t_last));
        t_end = ctx.clock().t_ticks + ctx.read(res::dt).dt_ticks;
    }
    const Count total = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, rows ? rows->size() : x.size(), 4096), Count{},
        [&](const auto& r, Count count) {
            for (std::size_t k = r.begin(); k < r.end(); ++k) {
                const std::size_t i = rows ? (*rows)[k] : k;
                Vec3 xi = x[i], vi = v[i];
                if (m_active_rows) {
                    const Real dt = drift_interval(t_end, t_last[i]);
                    vi = drifted_velocity(v0[i], acc[i], dt);
                    xi = drifted_position(x0[i], vi, dt);
                }
                const Vec3 x_end = xi;  // before the net
                bool hit = false, moving_hit = false;
                if (!any_moving) {
                    for (const auto& b : boundaries) hit |= collide(b, xi, vi);
                } else {
                    for (std::size_t j = 0; j < boundaries.size(); ++j) {
                        // Reflect/clamp the velocity relative to the body (Ihmsen 2010 eq. 11-12
                        // in the body's frame), then return to the world frame.
                        Vec3 rel = vi - body_velocity[j];
                        if (collide(boundaries[j], xi, rel)) {
                            vi = rel + body_velocity[j];
                            hit = true;
                            moving_hit |= boundaries[j].motion.has_value();
                        }
                    }
                }
                if (hit) {
                    if (m_active_rows && !moving_hit) count.shift = std::max(count.shift, double((xi - x_end).norm()));
                    count.moving |= moving_hit;
                    x[i] = xi;
                    v[i] = vi;
                }
                // Individual stepping: the corrected state must become the particle's base
                // state, so it is evaluated at the next step (SelectActiveSystem reads wake).
                if (hit && !wake.empty()) wake[i] = 1;
                // Binned stepping: the same, through the list BinnedWakeSystem reads.
                if (hit && m_active_rows) hits.local().push_back(Index(i));
                count.hits += hit;
                count.droplets += hit && lists && lists->of(i).empty();
            }
            return count;
        },
        [](Count a, Count b) {
            return Count{a.hits + b.hits, a.droplets + b.droplets, std::max(a.shift, b.shift), a.moving || b.moving};
        });
    ctx.write(counter::collisions) = total.hits;
    if (m_count_droplets) ctx.write(counter::droplet_contacts) = total.droplets;
    if (m_active_rows) {
        auto& out = ctx.write(res::collided);
        out.clear();
        for (const auto& v : hits) out.insert(out.end(), v.begin(), v.end());
        std::sort(out.begin(), out.end());
        // The jump in float, with a margin for its own rounding (FluidGridSystem adds the
        // rounding of the drifted positions apart); a moving body's hit may speed a row up.
        DriftBound& bound = ctx.write(res::drift_bound);
        bound.net_shift_static = total.shift * 1.001;
        bound.net_shift = total.moving ? std::numeric_limits<double>::infinity() : bound.net_shift_static;
    }
}

void BoundaryCollisionSystem::summarise(const World&, const RunTotals& totals, nlohmann::json& j) const {
    if (m_count_droplets) j["droplet_contacts_total"] = std::uint64_t(totals.counter_sum(counter::droplet_contacts.name));
}

}  // namespace sph
