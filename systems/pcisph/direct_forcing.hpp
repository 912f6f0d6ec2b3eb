#pragma once
/// @file direct_forcing.hpp
/// @brief Direct forcing, Ihmsen et al. 2010 eq. 9-11 (position) and, on final positions,
/// eq. 12 (velocity: v = eps [v]_t in the boundary's frame): the loop shared by
/// PredictCollisionSystem (on x*, inside the loop) and WorldCollisionSystem (on x, v after
/// integration). The per-pair maths is DirectForcing in pcisph_kernels.hpp.
namespace sph {

class Context;

/// @brief Applies eq. 9-11 (and eq. 12 unless `predicted`) to every fluid particle near a
/// boundary particle; the caller's Access declares what is touched (see the two systems).
void direct_forcing(Context& ctx, bool predicted, bool moving, double friction);

}  // namespace sph
