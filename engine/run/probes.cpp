/// @file probes.cpp
/// @brief Probe measurement (parsing: engine/probe_desc.cpp). Interpolation is standard SPH
/// (Monaghan 1992, J. Comput. Phys.; Shepard normalisation for point values); wall pressure is
/// Adami, Hu & Adams 2012 (J. Comput. Phys. 231:7057) eq. 27.
#include "engine/run/probes.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include <nlohmann/json.hpp>

#include "engine/data/components.hpp"
#include "engine/core/errors.hpp"
#include "engine/run/io.hpp"
#include "engine/data/world.hpp"

namespace sph {

// ---------------------------------------------------------------------------------------------
// Measurements
// ---------------------------------------------------------------------------------------------
namespace {
/// Particle volume m / rho_j; before the first step has computed densities (t = 0, the column
/// still zero) the lattice's rest volume m / rho0.
inline double volume(const World& w, Real rho_j) {
    return double(w.physics.mass) / double(rho_j > Real(0) ? rho_j : w.physics.rest_density);
}
}  // namespace

double colour_at(const World& w, const UniformGrid& grid, const Vec3d& x) {
    const auto rho = w.fluid.store.get(comp::density);
    const Vec3 xf = x.cast<Real>();
    double c = 0;
    grid.for_each_candidate(xf, w.fluid.store.get(comp::position), [&](Index j, const Vec3& xj) { c += volume(w, rho[j]) * double(w.kernel.w((xf - xj).norm())); });
    return c;
}

double fluid_pressure_at(const World& w, const UniformGrid& grid, const Vec3d& x, double* colour) {
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const Vec3 xf = x.cast<Real>();
    double num = 0, den = 0;
    grid.for_each_candidate(xf, w.fluid.store.get(comp::position), [&](Index j, const Vec3& xj) {
        const double vw = volume(w, rho[j]) * double(w.kernel.w((xf - xj).norm()));
        num += vw * double(p[j]);
        den += vw;
    });
    if (colour) *colour = den;
    return den > 0 ? num / den : 0.0;
}

double boundary_pressure_at(const World& w, const UniformGrid& grid, const Vec3d& point, double radius, int* count) {
    const auto xb = w.boundary.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const Vec3d g = w.physics.gravity.cast<double>();
    double sum = 0;
    int n = 0;
    for (std::size_t b = 0; b < xb.size(); ++b) {
        const Vec3d x = xb[b].cast<double>();
        if ((x - point).norm() > radius) continue;
        double pw = 0, ww = 0;
        Vec3d rw = Vec3d::Zero();
        grid.for_each_candidate(xb[b], w.fluid.store.get(comp::position), [&](Index f, const Vec3& xf) {
            const double wbf = w.kernel.w((xb[b] - xf).norm());
            pw += double(p[f]) * wbf;
            rw += double(rho[f] > Real(0) ? rho[f] : w.physics.rest_density) * (x - xf.cast<double>()) * wbf;
            ww += wbf;
        });
        if (ww <= 0) continue;
        sum += (pw + g.dot(rw)) / ww;  // Adami et al. 2012 eq. 27 with a_w = 0
        ++n;
    }
    if (count) *count = n;
    return n ? sum / n : 0.0;
}

double sensor_pressure_at(const World& w, const UniformGrid& grid, const Vec3d& point, const Vec3d& normal,
                          double diameter, double* wet) {
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const Vec3d g = w.physics.gravity.cast<double>();
    // Two unit vectors in the face.
    const Vec3d n = normal.normalized();
    const Vec3d e1 = (std::abs(n.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(n).normalized();
    const Vec3d e2 = n.cross(e1);
    const double R = 0.5 * diameter, ds = 0.25 * double(w.physics.spacing);
    const int rings = std::max(1, int(std::ceil(R / ds)));
    double sum = 0, area = 0, wet_area = 0;
    for (int k = 0; k < rings; ++k) {
        const double r0 = R * k / rings, r1 = R * (k + 1) / rings, rm = 0.5 * (r0 + r1);
        const double ring_area = M_PI * (r1 * r1 - r0 * r0);
        const int m = k == 0 ? 1 : std::max(6, int(std::ceil(2 * M_PI * rm / ds)));
        for (int a = 0; a < m; ++a) {
            const double phi = 2 * M_PI * (a + 0.5) / m;
            const Vec3d x = k == 0 && m == 1 ? point : Vec3d(point + rm * (std::cos(phi) * e1 + std::sin(phi) * e2));
            const Vec3 xf = x.cast<Real>();
            double pw = 0, ww = 0, colour = 0;
            Vec3d rw = Vec3d::Zero();
            grid.for_each_candidate(xf, w.fluid.store.get(comp::position), [&](Index f, const Vec3& xj) {
                const double wf = w.kernel.w((xf - xj).norm());
                pw += double(p[f]) * wf;
                rw += double(rho[f] > Real(0) ? rho[f] : w.physics.rest_density) * (x - xj.cast<double>()) * wf;
                ww += wf;
                colour += volume(w, rho[f]) * wf;
            });
            const double da = ring_area / m;
            area += da;
            // Wet where the colour is at least half a wetted wall's (0.5: no fluid beyond it).
            if (ww > 0 && colour >= 0.25) sum += da * (pw + g.dot(rw)) / ww, wet_area += da;  // Adami et al. 2012 eq. 27
        }
    }
    if (wet) *wet = area > 0 ? wet_area / area : 0.0;
    return area > 0 ? sum / area : 0.0;
}

double iso_distance(const World& w, const UniformGrid& grid, const Vec3d& from, const Vec3d& to) {
    const double length = (to - from).norm();
    const int n = std::max(1, int(std::ceil(length / (0.25 * double(w.physics.spacing)))));
    const auto at = [&](double s) { return colour_at(w, grid, from + (to - from) * (s / length)); };
    // The farthest wet sample (c >= 0.5). The start need not be wet: on a wall the colour is
    // about 0.5 (no fluid beyond it).
    int last_wet = -1;
    for (int k = 0; k <= n; ++k)
        if (at(length * k / n) >= 0.5) last_wet = k;
    if (last_wet < 0) return 0.0;
    if (last_wet == n) return length;
    // Bisection between it and the dry sample after it, to a thousandth of a spacing.
    double s0 = length * last_wet / n, s1 = length * (last_wet + 1) / n;
    while (s1 - s0 > 1e-3 * double(w.physics.spacing)) {
        const double mid = 0.5 * (s0 + s1);
        (at(mid) >= 0.5 ? s0 : s1) = mid;
    }
    return 0.5 * (s0 + s1);
}

double column_height(const World& w, const UniformGrid& grid, const Vec3d& from, const Vec3d& to) {
    const double length = (to - from).norm(), spacing = double(w.physics.spacing);
    const int n = std::max(1, int(std::ceil(length / (0.25 * spacing))));
    const double ds = length / n;
    const auto wet = [&](double s) { return colour_at(w, grid, from + (to - from) * (s / length)) >= 0.5; };
    // The column starts within one kernel support h of `from` (on a floor the colour is about
    // 0.5, half the support being below it, and less in a corner between floor and wall), else
    // there is no water here.
    const double h = double(w.physics.h);
    int k = 0;
    while (k <= n && k * ds <= h && !wet(k * ds)) ++k;
    if (k > n || k * ds > h) return 0.0;
    // Its top: the start of the first dry stretch at least one spacing long (a gap the size of a
    // particle is a bubble or noise, not the end of the water).
    const int gap = std::max(1, int(std::ceil(spacing / ds)));
    int dry = 0;
    for (; k <= n && dry < gap; ++k) dry = wet(k * ds) ? 0 : dry + 1;
    if (dry == 0) return length;  // wet to the line's end
    // Bisection between the last wet sample and the first of the dry stretch (which may be
    // shorter than a spacing where it reaches the line's end).
    double s0 = (k - dry - 1) * ds, s1 = (k - dry) * ds;
    while (s1 - s0 > 1e-3 * spacing) {
        const double mid = 0.5 * (s0 + s1);
        (wet(mid) ? s0 : s1) = mid;
    }
    return 0.5 * (s0 + s1);
}

double front_by_neighbours(const World& w, const UniformGrid& grid, const Vec3d& dir, int k) {
    const auto x = w.fluid.store.get(comp::position);
    const Vec3 d = dir.cast<Real>();
    std::vector<Index> order(x.size());
    std::iota(order.begin(), order.end(), Index(0));
    std::vector<Real> proj(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) proj[i] = x[i].dot(d);
    // The rows in order of decreasing projection (ties by index), taken lazily from a heap: the
    // front is usually among the first few, so O(n) for the heap instead of a sort's O(n log n).
    const auto later = [&](Index a, Index b) { return proj[b] > proj[a] || (proj[b] == proj[a] && b < a); };
    std::make_heap(order.begin(), order.end(), later);
    const Real h2 = w.physics.h * w.physics.h;
    for (auto end = order.end(); end != order.begin(); --end) {
        std::pop_heap(order.begin(), end, later);
        const Index i = *(end - 1);
        int count = 0;
        grid.for_each_candidate(x[i], w.fluid.store.get(comp::position), [&](Index j, const Vec3& xj) {
            if (j != i && (x[i] - xj).squaredNorm() < h2) ++count;
        });
        if (count >= k) return double(proj[i]);
    }
    return -std::numeric_limits<double>::infinity();
}

FluidTotals fluid_totals(const World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    const double m = w.physics.mass, rho0 = w.physics.rest_density;
    const Vec3d g = w.physics.gravity.cast<double>();
    // Deterministic: the same sums whatever the thread count.
    FluidTotals t = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, x.size(), 1024), FluidTotals{},
        [&](const auto& r, FluidTotals a) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Vec3d vi = v[i].template cast<double>();
                a.kinetic += 0.5 * m * vi.squaredNorm();
                a.potential -= m * g.dot(x[i].template cast<double>());
                a.momentum += m * vi;
                a.centre += x[i].template cast<double>();
                const double e = std::max(0.0, double(rho[i]) / rho0 - 1.0);
                a.rho_err_avg += e;
                a.rho_err_max = std::max(a.rho_err_max, e);
            }
            return a;
        },
        [](FluidTotals a, const FluidTotals& b) {
            a.kinetic += b.kinetic;
            a.potential += b.potential;
            a.momentum += b.momentum;
            a.centre += b.centre;
            a.rho_err_avg += b.rho_err_avg;
            a.rho_err_max = std::max(a.rho_err_max, b.rho_err_max);
            return a;
        });
    if (!x.empty()) {
        t.rho_err_avg /= double(x.size());
        t.centre /= double(x.size());
    }
    return t;
}

InteriorDensityError interior_density_error(const World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    const bool walls = w.boundary.size() > 0;
    const double rho0 = w.physics.rest_density;
    const Real h2 = w.physics.h * w.physics.h;
    struct Acc {
        double sum = 0, max = 0;
        std::size_t n = 0;
    };
    // Deterministic, as fluid_totals.
    const Acc a = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, x.size(), 1024), Acc{},
        [&](const auto& r, Acc acc) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                // The world's boundary grid (kept current by the boundary motion system).
                bool near_wall = false;
                if (walls)
                    w.boundary_grid.for_each_candidate(x[i], w.boundary.store.get(comp::position), [&](Index, const Vec3& xbj) {
                        if (!near_wall) near_wall = (x[i] - xbj).squaredNorm() < h2;  // the rest unread
                    });
                if (near_wall) continue;
                const double e = std::max(0.0, double(rho[i]) / rho0 - 1.0);
                acc.sum += e;
                acc.max = std::max(acc.max, e);
                ++acc.n;
            }
            return acc;
        },
        [](Acc l, const Acc& r) { return Acc{l.sum + r.sum, std::max(l.max, r.max), l.n + r.n}; });
    return {a.n ? a.sum / double(a.n) : 0.0, a.max, a.n};
}

// ---------------------------------------------------------------------------------------------
// ProbeSet
// ---------------------------------------------------------------------------------------------

std::vector<double> ProbeSeries::column(const std::string& c) const {
    const auto it = std::find(columns.begin(), columns.end(), c);
    if (it == columns.end()) throw std::out_of_range("probe " + name + " has no column " + c);
    const std::size_t k = std::size_t(it - columns.begin());
    std::vector<double> out;
    out.reserve(rows.size());
    for (const auto& r : rows) out.push_back(r[k]);
    return out;
}

std::string ProbeSeries::csv() const {
    std::ostringstream os;
    os.precision(9);
    for (std::size_t c = 0; c < columns.size(); ++c) os << (c ? "," : "") << columns[c];
    os << '\n';
    for (const auto& r : rows) {
        for (std::size_t c = 0; c < r.size(); ++c) os << (c ? "," : "") << r[c];
        os << '\n';
    }
    return os.str();
}

ProbeSet::ProbeSet(const std::vector<ProbeDesc>& probes) : m_probes(probes), m_taken(probes.size(), 0) {
    for (const ProbeDesc& d : probes) {
        ProbeSeries s;
        s.name = d.name;
        switch (d.type) {
            case ProbeType::Pressure:
                s.columns = d.source == PressureSource::Fluid      ? std::vector<std::string>{"t", "p", "colour"}
                            : d.source == PressureSource::Boundary ? std::vector<std::string>{"t", "p", "wall_particles"}
                                                                   : std::vector<std::string>{"t", "p", "wet"};
                break;
            case ProbeType::Height:
                s.columns = {"t", "height", "x", "y", "z"};
                break;
            case ProbeType::Front:
                s.columns = d.method == FrontMethod::Neighbours ? std::vector<std::string>{"t", "front", "x_centre"}
                                                                : std::vector<std::string>{"t", "front"};
                break;
            case ProbeType::Fluid:
                s.columns = {"t", "kinetic", "potential", "momentum_x", "momentum_y", "momentum_z", "rho_err_avg",
                             "rho_err_max", "rho_err_avg_interior", "rho_err_max_interior", "interior_count",
                             "centre_x", "centre_y", "centre_z"};
                break;
        }
        m_series.push_back(std::move(s));
    }
}

const ProbeSeries& ProbeSet::series(const std::string& name) const {
    for (const auto& s : m_series)
        if (s.name == name) return s;
    throw std::out_of_range("no probe named " + name);
}

void ProbeSet::sample(std::size_t k, const World& w, const UniformGrid& grid) {
    const ProbeDesc& d = m_probes[k];
    std::vector<double> row{w.clock.t};
    switch (d.type) {
        case ProbeType::Pressure:
            if (d.source == PressureSource::Fluid) {
                double c = 0;
                const double p = fluid_pressure_at(w, grid, d.point, &c);
                row.insert(row.end(), {p, c});
            } else if (d.source == PressureSource::Sensor) {
                double wet = 0;
                const double p = sensor_pressure_at(w, grid, d.point, d.normal, d.diameter, &wet);
                row.insert(row.end(), {p, wet});
            } else {
                int n = 0;
                const double radius = d.radius > 0 ? d.radius : 2.0 * double(w.physics.spacing);
                const double p = boundary_pressure_at(w, grid, d.point, radius, &n);
                row.insert(row.end(), {p, double(n)});
            }
            break;
        case ProbeType::Height: {
            const double s = d.height_method == HeightMethod::Column ? column_height(w, grid, d.from, d.to)
                                                                     : iso_distance(w, grid, d.from, d.to);
            const Vec3d at = d.from + (d.to - d.from).normalized() * s;
            row.insert(row.end(), {s, at.x(), at.y(), at.z()});
            break;
        }
        case ProbeType::Front:
            if (d.method == FrontMethod::Neighbours) {
                // The particle stands for a cube of one spacing: the fluid ends r = spacing/2
                // beyond its centre (a block filled from 0 to a reports a at t = 0).
                const double c = front_by_neighbours(w, grid, d.direction, d.min_neighbours);
                const double r = double(w.physics.particle_radius);
                row.insert(row.end(), {std::isfinite(c) ? c + r : 0.0, std::isfinite(c) ? c : 0.0});
            } else {
                const double s = iso_distance(w, grid, d.from, d.to);
                row.push_back((d.from + d.direction * s).dot(d.direction));
            }
            break;
        case ProbeType::Fluid: {
            const FluidTotals t = fluid_totals(w);
            const InteriorDensityError in = interior_density_error(w);
            row.insert(row.end(), {t.kinetic, t.potential, t.momentum.x(), t.momentum.y(), t.momentum.z(),
                                   t.rho_err_avg, t.rho_err_max, in.rho_err_avg, in.rho_err_max,
                                   double(in.count), t.centre.x(), t.centre.y(), t.centre.z()});
            break;
        }
    }
    m_series[k].rows.push_back(std::move(row));
    ++m_taken[k];
}

bool ProbeSet::any_due(double t) const {
    for (std::size_t k = 0; k < m_probes.size(); ++k)
        if (t + 1e-12 >= double(m_taken[k]) / m_probes[k].rate) return true;
    return false;
}

void ProbeSet::sample_due(const World& w) {
    std::vector<std::size_t> due;
    const double t = w.clock.t;
    for (std::size_t k = 0; k < m_probes.size(); ++k) {
        // Sample k is due at k / rate; a step that passes several sample times samples once.
        if (t + 1e-12 >= double(m_taken[k]) / m_probes[k].rate) due.push_back(k);
    }
    if (due.empty()) return;
    UniformGrid grid(w.domain, w.physics.h);
    grid.build(w.fluid.store.get(comp::position));
    for (const std::size_t k : due) {
        sample(k, w, grid);
        m_taken[k] = std::max<std::int64_t>(m_taken[k], std::int64_t(std::floor(t * m_probes[k].rate + 1e-9)) + 1);
    }
}

void ProbeSet::sample_all(const World& w) {
    if (m_probes.empty()) return;
    UniformGrid grid(w.domain, w.physics.h);
    grid.build(w.fluid.store.get(comp::position));
    for (std::size_t k = 0; k < m_probes.size(); ++k) sample(k, w, grid);
}

void ProbeSet::write(const std::filesystem::path& dir) const {
    if (m_series.empty()) return;
    std::filesystem::create_directories(dir / "probes");
    for (const auto& s : m_series) write_file_atomic(dir / "probes" / (s.name + ".csv"), s.csv());
}

nlohmann::json ProbeSet::state() const {
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t k = 0; k < m_series.size(); ++k) {
        nlohmann::json rows = nlohmann::json::array();
        for (const auto& r : m_series[k].rows) {
            nlohmann::json row = nlohmann::json::array();
            for (const double v : r) row.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
            rows.push_back(std::move(row));
        }
        out.push_back({{"name", m_series[k].name}, {"columns", m_series[k].columns}, {"taken", m_taken[k]},
                       {"rows", std::move(rows)}});
    }
    return out;
}

void ProbeSet::restore(const nlohmann::json& st) {
    const auto mismatch = [](const std::string& what) {
        throw InputError("checkpoint probes: " + what + " (the checkpoint was written by another scene)");
    };
    if (!st.is_array() || st.size() != m_series.size())
        mismatch("expected " + std::to_string(m_series.size()) + " probe series");
    for (std::size_t k = 0; k < m_series.size(); ++k) {
        const nlohmann::json& s = st[k];
        if (s.value("name", std::string()) != m_series[k].name ||
            s.value("columns", std::vector<std::string>()) != m_series[k].columns)
            mismatch("series " + std::to_string(k) + " is not probe '" + m_series[k].name + "' with its columns");
        std::vector<std::vector<double>> rows;
        for (const auto& row : s.at("rows")) {
            if (row.size() != m_series[k].columns.size()) mismatch("a row of '" + m_series[k].name + "' has the wrong width");
            std::vector<double>& r = rows.emplace_back();
            for (const auto& v : row) r.push_back(v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>());
        }
        m_series[k].rows = std::move(rows);
        m_taken[k] = s.at("taken").get<std::int64_t>();
    }
}

}  // namespace sph
