#pragma once
/// @file step_bound_simd.hpp
/// @brief The per-particle step of He et al. Alg. 2 line 13 (eq. 6-8 per particle, with the
/// acoustic condition), Delta t_i^raw = StepBound(|v_i|, |a_i|), for a range of rows,
/// vectorised across rows. Bit for bit StepBound's: the squared norms in the particle
/// precision summed in the order of Eigen 3.4's unrolled reduction, x^2 + (y^2 + z^2), the
/// roots and quotients in double (IEEE-exact in every lane), min taken as std::min takes it (a
/// NaN never replaces the bound), and no contracted multiply-add (the file is compiled with
/// -ffp-contract=off).
#include <cstddef>

#include "engine/core/types.hpp"
#include "systems/timestep/global_dt_system.hpp"

namespace sph {

/// @brief dt_raw[i] = bound(|v_i|, |a_i|) for i = rows[k] (or i = k when rows is null), k in
/// [begin, end); v and a are xyz rows of `n` particles. Float builds only (SPH_DOUBLE runs the
/// scalar loop: Physics::simd is off there).
void step_bounds_simd(const StepBound& bound, const Real* v, const Real* a, std::size_t n, const Index* rows,
                      std::size_t begin, std::size_t end, double* dt_raw);

}  // namespace sph
