#pragma once
/// @file drift.hpp
/// @brief He et al. Alg. 2 lines 19-21 and line 9 for one row: its state at time t from its
/// base state (x, v, rho at its last evaluation t_last, and a, drho/dt evaluated then). The
/// one expression every system that advances or drifts a row uses, so that a row drifted late
/// (binned stepping's lazy drift) holds the same bits as one advanced every step.
#include "engine/data/world.hpp"

namespace sph {

/// Delta t = t - t_last_i in seconds, as He line 19 takes it.
inline Real drift_interval(Tick t, std::int64_t t_last) { return Real(to_seconds(t - t_last)); }

/// v_i = v_i(t_last) + Delta t a_i (line 20).
inline Vec3 drifted_velocity(const Vec3& v0, const Vec3& a, Real dt) { return v0 + dt * a; }

/// x_i = x_i(t_last) + Delta t v_i, with the line-20 velocity (line 21).
inline Vec3 drifted_position(const Vec3& x0, const Vec3& v, Real dt) { return x0 + dt * v; }

/// x_i at `now` from the base state, lines 20-21 together (the position the drift places).
inline Vec3 position_at(Tick now, std::int64_t t_last, const Vec3& x0, const Vec3& v0, const Vec3& a) {
    const Real dt = drift_interval(now, t_last);
    return drifted_position(x0, drifted_velocity(v0, a, dt), dt);
}

/// x_i at `now` read from the base state alone: a row evaluated at `now` holds x = x_last (what a
/// system that does not wait for the drift's placement computes in its place).
inline Vec3 position_from_base(Tick now, std::int64_t t_last, const Vec3& x0, const Vec3& v0, const Vec3& a) {
    return t_last == now ? x0 : position_at(now, t_last, x0, v0, a);
}

/// rho_i = rho_i(t_last) + Delta t drho_i/dt (line 9; He eq. 5 gives the slope).
inline Real drifted_density(Real rho0, Real drho, Real dt) { return rho0 + dt * drho; }

}  // namespace sph
