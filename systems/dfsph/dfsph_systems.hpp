#pragma once
/// @file dfsph_systems.hpp
/// @brief The phases of divergence-free SPH (Bender & Koschier 2015, 2017 Alg. 1), each a
/// flow-graph system with declared reads and writes (systems/methods/dfsph.cpp orders them):
///   dfsph_dt -> grid, neighbours -> dfsph_factor -> dfsph_divergence_warm ->
///   dfsph_divergence { dfsph_divergence_pressure -> dfsph_divergence_source } x k ->
///   nonpressure_forces -> dfsph_predict -> dfsph_wall_contact -> dfsph_density_warm ->
///   dfsph_density { dfsph_density_pressure -> dfsph_density_source } x k ->
///   dfsph_integrate -> boundary_collision (safety net) -> step_stats.
/// The paper's divergence solve at the end of step n (after the neighbour search and the
/// factors of the new positions) is here the first solve of step n + 1: the same operations
/// in the same order, so a step's neighbour search and factors serve both solvers.
///
/// Volume form: V = m / rho0 (fluid), V_b (Akinci et al. 2012 eq. 4, boundary), rho relative to
/// rho0, and the stiffness k_i = kappa_i / rho_i * rho0 of the paper, so that a pass moves
///   v_i -= dt (sum_j V (k_i + k_j) grad W_ij + sum_b V_b k_i grad W_ib)        (eq. 13, 17)
/// with, for the density solver (eq. 12), k_i = max(rho*_i/rho0 - 1, 0) factor_i / dt^2,
///   rho*_i/rho0 = rho_i/rho0 + dt sum_j V (v_i - v_j).grad W_ij + dt sum_b V_b (v_i - v_b).grad W_ib,
/// and for the divergence solver (eq. 16), k_i = max(Drho_i/Dt / rho0, 0) factor_i / dt, where
/// factor_i = 1 / (|sum_j V grad W_ij + sum_b V_b grad W_ib|^2 + sum_j |V grad W_ij|^2) (eq. 11).
#include <string>

#include "engine/graph/system.hpp"
#include "systems/dfsph/dfsph_state.hpp"

namespace sph {

/// @brief The step: `adaptive` takes the CFL step dt = cfl 2 r / v_max (eq. 20 with the
/// particle diameter), at most dt_max; the last step of a run is split as PCISPH's is (a
/// sliver of a step would make dt^-2 stiffnesses). Summarises the solvers' passes.
class DfsphStepSizeSystem final : public System {
public:
    DfsphStepSizeSystem(bool adaptive, double cfl, double dt_max, double eta, double eta_divergence)
        : m_adaptive(adaptive), m_cfl(cfl), m_dt_max(dt_max), m_eta(eta), m_eta_divergence(eta_divergence) {}
    std::string name() const override { return "dfsph_dt"; }
    Access access() const override;
    void run(Context& ctx) override;
    /// @brief summary.json "dfsph": average passes of each solver and the targets.
    void summarise(const World& w, const RunTotals& totals, nlohmann::json& summary) const override;

private:
    bool m_adaptive;
    double m_cfl, m_dt_max, m_eta, m_eta_divergence;
};

/// @brief Summation density (Akinci et al. 2012 eq. 6: rho_i = m sum_j W_ij + rho0 sum_b V_b W_ib,
/// j = i included) and the factor of eq. 11 at the step's positions; for the solver passes, the
/// boundary's sums per particle and (vectorised loops) V grad W_ij of every fluid pair.
/// With `viscosity` it also writes the viscous acceleration of NonpressureForcesSystem (the
/// same formulas) from the pairs it reads anyway, one pass over the neighbours fewer per step.
/// It then reads the velocities before the divergence solve where Alg. 1 reads them after it;
/// the divergence solve changes a velocity by its compression rate times h (below 0.1 % per
/// step at eta_divergence), which the viscosity sees at second order.
class DfsphFactorSystem final : public System {
public:
    DfsphFactorSystem(bool boundary, bool moving = false, bool viscosity = false)
        : m_boundary(boundary), m_moving(moving), m_viscosity(viscosity) {}
    std::string name() const override { return "dfsph_factor"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_boundary, m_moving, m_viscosity;
};

/// @brief Sets a solver's first stiffness: half of what it applied over the last step (warm
/// start, Bender & Koschier 2017 sec. 4.3; 0 without warm start), rescaled to this step's dt.
class DfsphWarmStartSystem final : public System {
public:
    DfsphWarmStartSystem(DfsphSolver solver, bool warm) : m_solver(solver), m_warm(warm) {}
    std::string name() const override;
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    DfsphSolver m_solver;
    bool m_warm;
};

/// @brief One pressure pass: v_i -= dt a_i with a_i of eq. 13 / 17 from the current stiffness
/// (and, for the density solver, the acceleration column follows: a_i -= a^p_i).
class DfsphPressureSystem final : public System {
public:
    DfsphPressureSystem(DfsphSolver solver, bool boundary) : m_solver(solver), m_boundary(boundary) {}
    std::string name() const override;
    Access access() const override;
    void run(Context& ctx) override;

private:
    DfsphSolver m_solver;
    bool m_boundary;
};

/// @brief The source term of a solver from the current velocities (eq. 8 / eq. 16), the next
/// pass's stiffness, the running total for the warm start, the solver's average error, and for
/// the density solver the pressure p_i = rho0 sum k_i it has applied (outputs and probes).
class DfsphSourceSystem final : public System {
public:
    /// @param min_neighbours divergence solver: particles with fewer neighbours (fluid and
    /// boundary) take no divergence correction (a free-surface particle's deficient
    /// neighbourhood reads as expansion); Bender's SPlisHSPlasH uses 20 in 3-D.
    /// @param relaxation omega of the Jacobi update, k_i = omega src_i factor_i / dt^2 (1: Bender
    /// & Koschier's; above 1, over-relaxation, docs/methods.md "DFSPH").
    DfsphSourceSystem(DfsphSolver solver, bool boundary, bool moving, double relaxation = 1.0, int min_neighbours = 20)
        : m_solver(solver), m_boundary(boundary), m_moving(moving), m_relaxation(relaxation),
          m_min_neighbours(min_neighbours) {}
    std::string name() const override;
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    DfsphSolver m_solver;
    bool m_boundary, m_moving;
    double m_relaxation;
    int m_min_neighbours;
};

/// @brief Alg. 1 lines 4-6: a_i = g + a^nonp_i (viscosity, surface tension) and v*_i = v_i + dt a_i.
class DfsphPredictSystem final : public System {
public:
    explicit DfsphPredictSystem(bool nonpressure) : m_nonpressure(nonpressure) {}
    std::string name() const override { return "dfsph_predict"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_nonpressure;
};

/// @brief Contact with the walls on the predicted velocities: a particle within r0 = h / 2 of
/// boundary particles and moving into them (relative to the wall) loses that normal
/// component, n from Ihmsen et al. 2010 eq. 9-10 (the weighted boundary normals), as eq. 12
/// does with friction 1 (free slip). Akinci's boundary pressure only acts on compressed
/// particles, so a drop or a thin sheet (a pour into a glass) would otherwise run into the
/// wall; here the density solver sees velocities that respect it. No position is moved.
class DfsphWallContactSystem final : public System {
public:
    explicit DfsphWallContactSystem(bool moving) : m_moving(moving) {}
    std::string name() const override { return "dfsph_wall_contact"; }
    Access access() const override;
    void register_components(World& w) override;  ///< the boundary's normals
    void run(Context& ctx) override;

private:
    bool m_moving;
};

/// @brief Alg. 1 line 8: x_i += dt v*_i (v*_i, corrected by the density solver, is the new velocity).
class DfsphIntegrateSystem final : public System {
public:
    std::string name() const override { return "dfsph_integrate"; }
    Access access() const override;
    void run(Context& ctx) override;
};

}  // namespace sph
