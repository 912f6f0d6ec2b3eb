#pragma once
// Comparison of a probe series with measured data (data/validation/*.csv, copied verbatim from
// ../shared/validation with their provenance headers). Same rules as tools/sph_study.py.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/run/probes.hpp"
#include "systems/methods/recipes.hpp"

namespace sph::test {

struct Points {
    std::vector<double> t, z;
};

/// Reads the columns `tcol` and `zcol` of a CSV whose '#' lines are comments and whose first
/// other line is the header.
inline Points read_points(const std::string& file, const std::string& tcol, const std::string& zcol) {
    std::ifstream f(file);
    if (!f) throw std::runtime_error("cannot open " + file);
    std::string line;
    std::vector<std::string> header;
    Points p;
    while (std::getline(f, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::vector<std::string> cells;
        std::stringstream ss(line);
        for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
        if (header.empty()) {
            header = cells;
            continue;
        }
        const auto at = [&](const std::string& c) {
            return std::stod(cells.at(std::size_t(std::find(header.begin(), header.end(), c) - header.begin())));
        };
        p.t.push_back(at(tcol));
        p.z.push_back(at(zcol));
    }
    return p;
}

/// Linear interpolation of (t, y) at x; clamped at the ends.
inline double interp(const std::vector<double>& t, const std::vector<double>& y, double x) {
    if (x <= t.front()) return y.front();
    if (x >= t.back()) return y.back();
    const auto k = std::size_t(std::upper_bound(t.begin(), t.end(), x) - t.begin());
    const double a = (x - t[k - 1]) / (t[k] - t[k - 1]);
    return y[k - 1] + a * (y[k] - y[k - 1]);
}

/// The simulated series in the experiment's units: T = t * t_scale, Z = (value - offset) * scale.
inline Points dimensionless(const ProbeSeries& s, const std::string& column, double t_scale, double value_scale,
                            double offset = 0.0) {
    Points p;
    const auto t = s.column("t"), v = s.column(column);
    for (std::size_t i = 0; i < t.size(); ++i) {
        p.t.push_back(t[i] * t_scale);
        p.z.push_back((v[i] - offset) * value_scale);
    }
    return p;
}

struct ShiftedError {
    double shift = 0;  ///< dT: the simulation is compared at T - dT (the lab gate opened late)
    double rms_rel = 0;
};

/// RMS relative error sqrt(mean(((Z_sim(T_k - dT) - Z_k) / Z_k)^2)) over the points with
/// t_min <= T_k <= t_max, minimised over one constant shift |dT| <= max_shift (steps of 0.005).
inline ShiftedError front_error(const Points& sim, const Points& exp, double t_min, double t_max, double max_shift) {
    ShiftedError best{0, 1e300};
    const int n = int(std::lround(max_shift / 0.005));
    for (int k = -n; k <= n; ++k) {
        const double shift = 0.005 * k;
        double sum = 0;
        int count = 0;
        for (std::size_t i = 0; i < exp.t.size(); ++i) {
            if (exp.t[i] < t_min || exp.t[i] > t_max) continue;
            const double e = (interp(sim.t, sim.z, exp.t[i] - shift) - exp.z[i]) / exp.z[i];
            sum += e * e;
            ++count;
        }
        const double rms = count ? std::sqrt(sum / count) : 1e300;
        if (rms < best.rms_rel) best = {shift, rms};
    }
    return best;
}

/// Largest |Z_sim(T_k - shift) - Z_k| over the points with T_k <= t_max.
inline double max_abs_error(const Points& sim, const Points& exp, double t_max, double shift) {
    double worst = 0;
    for (std::size_t i = 0; i < exp.t.size(); ++i)
        if (exp.t[i] <= t_max) worst = std::max(worst, std::abs(interp(sim.t, sim.z, exp.t[i] - shift) - exp.z[i]));
    return worst;
}

/// Runs a scene to its end time, sampling its probes; returns them.
inline ProbeSet run_with_probes(const Scene& scene, std::int64_t* steps = nullptr) {
    auto sim = make_simulation(scene);
    ProbeSet probes(scene.probes);
    probes.sample_due(sim->world());
    sim->run_until(scene.simulation.end_time, [&](const Simulation& s) { probes.sample_due(s.world()); });
    if (steps) *steps = sim->steps();
    return probes;
}

/// Every stepping mode the loader knows for `method` except `constant`: the adaptive modes a
/// validation must hold in (a mode added later joins with no new code).
inline std::vector<std::string> adaptive_modes() {
    std::vector<std::string> out;
    for (const auto& m : stepping_mode_names())
        if (m != "constant") out.push_back(m);
    return out;
}

}  // namespace sph::test
