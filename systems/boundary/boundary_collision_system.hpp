#pragma once
/// @file boundary_collision_system.hpp
/// @brief Safety net behind the particle boundary: a fluid particle whose centre ends a step
/// beyond a declared boundary surface (container wall, box or sphere) is put back on the
/// surface and loses its velocity into the wall (an inelastic contact, as in the direct
/// forcing of Ihmsen et al. 2010 eq. 9-12 without the particle-based normal).
///
/// The Akinci boundary force only acts on particles whose density exceeds rho0 (the Tait
/// pressure is clamped at zero), so a thin splash hitting a wall can cross the single
/// boundary layer. The number of particles corrected each step is reported
/// (`collisions` in stats.csv); it is zero when the particle boundary alone holds.
///
/// With `count_droplets` the corrected particles that have no fluid neighbour this step are
/// counted apart (`droplet_contacts`, a part of `collisions`; summary `droplet_contacts_total`).
/// Such a particle's density is its summation density, at most about 0.8 rho0 at a wall (see
/// DensitySystem), so it has no pressure and the wall none for it: the net is its contact, by
/// design. The rest of `collisions` is the fluid crossing the wall in spite of its pressure,
/// the figure that says whether the particle boundary holds.
#include <vector>

#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// Moving boundaries (`moving`): the surface is the declared one moved by the body's
/// displacement d(t + dt), where the body will be at the start of the next step, and the
/// relative velocity v - v_b(t + dt) is what gets its component into the body removed.
class BoundaryCollisionSystem final : public System {
public:
    /// @param boundaries the scene's boundaries (the surfaces to hold the fluid behind).
    /// @param active_rows binned stepping: net the active rows only (the particles evaluated
    /// this step; a sleeping one moves at most lambda_v h between its evaluations, so it is
    /// netted at the end of its next one), list the corrected ones in res::collided and the
    /// longest jump it gave one in DriftBound::net_shift.
    /// @param count_droplets read this step's fluid neighbour lists (of every row netted) and
    /// count the contacts of rows without fluid neighbours apart.
    explicit BoundaryCollisionSystem(std::vector<BoundaryDesc> boundaries, bool moving = false,
                                     bool active_rows = false, bool count_droplets = false)
        : m_boundaries(std::move(boundaries)), m_moving(moving), m_active_rows(active_rows),
          m_count_droplets(count_droplets) {}
    std::string name() const override { return "boundary_collision"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
    void summarise(const World& w, const RunTotals& totals, nlohmann::json& summary) const override;

private:
    std::vector<BoundaryDesc> m_boundaries;
    bool m_moving;
    bool m_active_rows;
    bool m_count_droplets;
};

}  // namespace sph
