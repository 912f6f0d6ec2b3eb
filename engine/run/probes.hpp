#pragma once
/// @file probes.hpp
/// @brief Samples a scene's probes (engine/probe_desc.hpp) at their rates and keeps each as a
/// CSV series in memory; Recorder writes them to `probes/<name>.csv`. Every probe reads the
/// current particle state (end of the step) through its own grid, so it is exact in every
/// stepping mode (individual stepping's inactive particles included).
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "engine/core/grid.hpp"
#include "engine/data/probe_desc.hpp"

namespace sph {

struct World;

/// @brief One probe's samples: `columns[0]` is "t" (s), `columns[1]` the primary value.
struct ProbeSeries {
    std::string name;
    std::vector<std::string> columns;
    std::vector<std::vector<double>> rows;
    /// @brief Values of one column (throws std::out_of_range for an unknown column).
    std::vector<double> column(const std::string& name) const;
    std::string csv() const;
};

// ---- Measurements (pure functions of the world; the grid indexes the fluid's positions). ----

/// @brief Colour function c(x) = sum_j (m / rho_j) W(x - x_j) (Monaghan 1992 interpolation of
/// the indicator 1): about 1 inside the fluid, 0 outside, 0.5 at the free surface.
double colour_at(const World& w, const UniformGrid& grid, const Vec3d& x);
/// @brief Shepard-normalised pressure at a point, sum_j p_j V_j W / sum_j V_j W, V_j = m/rho_j;
/// 0 where no particle reaches. Also returns the colour c(x) (unnormalised sum_j V_j W).
double fluid_pressure_at(const World& w, const UniformGrid& grid, const Vec3d& x, double* colour = nullptr);
/// @brief Wall pressure: mean over the boundary particles within `radius` of `point` of the
/// pressure extrapolated to each, Adami, Hu & Adams 2012 eq. 27 (static wall):
/// p_b = (sum_f p_f W_bf + g . sum_f rho_f (x_b - x_f) W_bf) / sum_f W_bf. Boundary particles
/// no fluid particle reaches are left out; `count` returns how many were averaged.
double boundary_pressure_at(const World& w, const UniformGrid& grid, const Vec3d& point, double radius,
                            int* count = nullptr);
/// @brief What a wall sensor with a circular face reads: the wall pressure averaged over the
/// face, a disc of `diameter` centred at `point` with unit normal `normal` (area-weighted
/// quadrature, rings of at most a quarter spacing). The wall pressure at a face point x is
/// extrapolated from the fluid as for boundary particles (Adami, Hu & Adams 2012 eq. 27,
/// static wall): sum_f (p_f + rho_f g . (x - x_f)) W / sum_f W. A point whose colour
/// sum_f V_f W is below 0.25 (half of a wetted wall's 0.5, there being no fluid beyond the wall)
/// is dry and reads 0 (gauge), as a sensor face in air does. `wet` receives the wetted share of
/// the face's area.
double sensor_pressure_at(const World& w, const UniformGrid& grid, const Vec3d& point, const Vec3d& normal,
                          double diameter, double* wet = nullptr);
/// @brief Distance from `from` along the segment to the farthest 0.5-crossing of the colour
/// function from wet (c >= 0.5) to dry (samples a quarter spacing apart, then bisection to
/// 0.001 spacing); 0 when no sample is wet, the length when the end is wet.
double iso_distance(const World& w, const UniformGrid& grid, const Vec3d& from, const Vec3d& to);
/// @brief The top of the continuous water column along the segment from `from` to `to` (metres
/// from `from`): the column must start within the kernel support h of `from`; its top is where
/// the colour falls through 0.5 at the start of the first dry stretch at least one spacing long
/// (bisected to 1e-3 spacing). Droplets and spray above such a gap do not count; 0 without a
/// column. (A height probe's default, `"method": "column"`; iso_distance is `"highest"`.)
double column_height(const World& w, const UniformGrid& grid, const Vec3d& from, const Vec3d& to);
/// @brief Largest projection on `dir` (unit) of a fluid particle centre with at least `k`
/// fluid neighbours within h (self excluded); -inf when none has.
double front_by_neighbours(const World& w, const UniformGrid& grid, const Vec3d& dir, int k);

/// @brief Whole-fluid quantities (SI): kinetic 1/2 sum m v^2, potential -sum m g . x (zero at
/// the origin), momentum sum m v, the centre of mass (1/N) sum x (a sloshing wave's surface
/// moves it: scenes/standing_wave.json), and the density error max(rho/rho0 - 1, 0) (as in
/// stats.csv) averaged and maximised over the fluid.
struct FluidTotals {
    double kinetic = 0, potential = 0;
    Vec3d momentum = Vec3d::Zero();
    Vec3d centre = Vec3d::Zero();
    double rho_err_avg = 0, rho_err_max = 0;
};
FluidTotals fluid_totals(const World& w);

/// @brief Density error (clamped at 0, as in fluid_totals) over the *interior* fluid only: the
/// particles with no boundary particle within the support h. Next to a wall the two boundary
/// handlings differ most (without boundary density the wall layer is under-dense and counts
/// as zero compression, lowering the whole-fluid average: Ihmsen et al. 2010 sec. 4.1 compares
/// the handlings on that average), so this measure compares them on the fluid both treat alike.
struct InteriorDensityError {
    double rho_err_avg = 0, rho_err_max = 0;
    std::size_t count = 0;  ///< interior particles
};
InteriorDensityError interior_density_error(const World& w);

/// @brief The probes of one run.
class ProbeSet {
public:
    ProbeSet() = default;
    explicit ProbeSet(const std::vector<ProbeDesc>& probes);
    bool empty() const { return m_probes.empty(); }
    /// @brief Samples every probe whose next sample time has come (all of them at t = 0).
    void sample_due(const World& w);
    /// @brief true when sample_due at time t would sample a probe.
    bool any_due(double t) const;
    /// @brief Samples every probe now, whatever its rate.
    void sample_all(const World& w);
    const std::vector<ProbeSeries>& series() const { return m_series; }
    const ProbeSeries& series(const std::string& name) const;
    /// @brief Writes `<dir>/probes/<name>.csv` for every probe (atomically).
    void write(const std::filesystem::path& dir) const;
    /// @brief Every series and sampling counter, for a checkpoint (numbers round-trip exactly;
    /// a NaN sample is stored as null).
    nlohmann::json state() const;
    /// @brief Continues from what state() saved, so a resumed run writes the whole series.
    /// Throws InputError if the saved probes are not this set's (names and columns).
    void restore(const nlohmann::json& st);

private:
    void sample(std::size_t k, const World& w, const UniformGrid& grid);
    std::vector<ProbeDesc> m_probes;
    std::vector<ProbeSeries> m_series;
    std::vector<std::int64_t> m_taken;  ///< samples taken per probe: next is due at taken / rate
};

}  // namespace sph
