#pragma once
/// @file boundary_volume_system.hpp
/// @brief Akinci et al. 2012, eq. 4: boundary particle volume V_b = 1 / sum_k W_bk over the
/// boundary particles k near b (b included). Fluid sees a boundary particle as the mass
/// psi_b = rho0 V_b, which makes a one-layer wall of uneven sampling act as a full one.
///
/// Our refinement: V_b is scaled by gamma = s^3 sum_{plane lattice} W, so that a flat wall
/// sampled at the fluid spacing s gets exactly the fluid particle volume s^3 and a particle
/// resting one spacing from it has exactly rho0. Unscaled, eq. 4 gives 1.36 s^3 with the cubic
/// spline at h = 2 s, and the first fluid layer starts 6 % over-dense (a 120 kPa pressure spike
/// in dam_break). Curved walls, edges and corners keep Akinci's relative correction.
///
/// Moving bodies: the sum runs over the particle's own rigid object (static boundaries, or
/// one moving body), so a body's volumes are constant under its translation and computed once.
#include <cstdint>
#include <vector>

#include "engine/core/kernel.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief gamma = s^3 sum_{i,j} W(s sqrt(i^2 + j^2)) over a plane square lattice.
Real boundary_volume_gamma(const CubicSpline& kernel, Real spacing);

/// @brief The rigid object of each of n boundary rows: 0 for the static boundaries, k + 1 for
/// the rows of bodies[k]; empty when nothing moves (every row one object). Sums over a
/// particle's own object (eq. 4 here, Ihmsen et al. 2010's boundary part of rho_b in
/// BoundaryMassSystem) are then invariant under the bodies' rigid motion.
std::vector<std::uint32_t> boundary_objects(std::size_t n, const std::vector<MovingBody>& bodies);

class BoundaryVolumeSystem final : public System {
public:
    std::string name() const override { return "boundary_volume"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
};

}  // namespace sph
