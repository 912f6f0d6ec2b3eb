#pragma once
/// @file pcisph_config.hpp
/// @brief The phases of PCISPH with Ihmsen et al. 2010 boundary handling (Alg. 2), each a
/// flow-graph system with declared reads and writes:
///   pcisph_dt -> [neighbours, boundary_active] -> nonpressure_forces -> pcisph_reset ->
///   pcisph_iterations { pcisph_predict -> predict_collision -> pcisph_density ||
///   pcisph_boundary_density -> pcisph_pressure_force } x k -> pcisph_integrate ->
///   world_collision -> boundary_collision (safety net) -> step_stats -> adaptive_dt.
namespace sph {

/// @brief What a scene's PCISPH recipe contains.
struct PcisphConfig {
    bool boundary = false;     ///< the scene has boundaries
    bool ihmsen = false;       ///< boundary density and pressure (eq. 13); false: direct forcing only
    bool moving = false;       ///< some boundary moves
    bool adaptive = false;     ///< `adaptive` stepping (else `constant`)
    bool nonpressure = false;  ///< viscosity or surface tension is on
};

}  // namespace sph
