/// @file
/// @brief Scene loading, part 3: validation, document -> Scene. Every error names the file, the JSON path, the value found and what was expected (format and ranges: scenes/README.md).
#include "engine/data/scene_detail.hpp"



#include <Eigen/Geometry>


#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
#include <string_view>
#include <system_error>
#include <utility>

#include "engine/core/errors.hpp"

namespace sph {

using namespace scene_detail;

namespace {

// A cylinder's bounding box: its two cap discs' extents around the base and top centres.
Aabb cylinder_box(const BoundaryDesc& b) {
    const Vec3d top = b.center + b.height * b.axis;
    Vec3d ext;
    for (int a = 0; a < 3; ++a) ext[a] = b.radius * std::sqrt(std::max(0.0, 1.0 - b.axis[a] * b.axis[a]));
    return Aabb{b.center.cwiseMin(top) - ext, b.center.cwiseMax(top) + ext};
}

// The bounding box of a mesh's vertices.
Aabb vertices_box(const std::vector<Vec3d>& vertices) {
    Aabb box{Vec3d::Constant(std::numeric_limits<double>::max()), Vec3d::Constant(std::numeric_limits<double>::lowest())};
    for (const auto& v : vertices) {
        box.min = box.min.cwiseMin(v);
        box.max = box.max.cwiseMax(v);
    }
    return box;
}

// Two triangles per cell, front (counter-clockwise) side up: the fluid is above a heightfield.
void heightfield_triangles(const Aabb& span, BoundaryDesc& b) {
    const int nz = int(b.heights.size()), nx = int(b.heights[0].size());
    b.vertices.clear();
    b.triangles.clear();
    for (int k = 0; k < nz; ++k)
        for (int i = 0; i < nx; ++i)
            b.vertices.emplace_back(span.min.x() + (span.max.x() - span.min.x()) * i / (nx - 1), b.heights[k][i],
                                    span.min.z() + (span.max.z() - span.min.z()) * k / (nz - 1));
    auto id = [nx](int i, int k) { return k * nx + i; };
    for (int k = 0; k + 1 < nz; ++k)
        for (int i = 0; i + 1 < nx; ++i) {
            // (x, z) -> (x, z+1) -> (x+1, z): normal (dz x dx) points up (+y).
            b.triangles.push_back({id(i, k), id(i, k + 1), id(i + 1, k)});
            b.triangles.push_back({id(i + 1, k), id(i, k + 1), id(i + 1, k + 1)});
        }
    // The declared span in x and z (the last vertex may round an ulp off it), the heights' range in y.
    const Aabb heights = vertices_box(b.vertices);
    b.box = span;
    b.box.min.y() = heights.min.y();
    b.box.max.y() = heights.max.y();
}

// ---- Validation: document -> Scene. ----

/// Allowed range of a number; open bounds by default ("> 0").
struct Range {
    double lo = -std::numeric_limits<double>::infinity();
    bool lo_inclusive = false;
    double hi = std::numeric_limits<double>::infinity();
    bool hi_inclusive = false;
    const char* unit = nullptr;

    bool contains(double x) const {
        return std::isfinite(x) && (lo_inclusive ? x >= lo : x > lo) &&
               (hi_inclusive ? x <= hi : x < hi);
    }
    std::string describe() const {
        std::string s = "a number";
        const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
        if (has_lo) s += (lo_inclusive ? " >= " : " > ") + fmt_num(lo);
        if (has_hi)
            s += std::string(has_lo ? " and" : "") + (hi_inclusive ? " <= " : " < ") + fmt_num(hi);
        if (unit) s += std::string(" (") + unit + ")";
        return s;
    }
};

Range positive(const char* unit) {
    return {0.0, false, Range{}.hi, false, unit};
}
Range non_negative(const char* unit) {
    return {0.0, true, Range{}.hi, false, unit};
}
Range any_number(const char* unit) {
    return {Range{}.lo, false, Range{}.hi, false, unit};
}
/// Times the clock holds: it counts whole picoseconds in 64 bits (engine/data/world.hpp), so
/// 1 ns is 1,000 ticks (rounding below 0.1 %) and 1e6 s leaves room for t + dt up to 9.2e6 s.
Range timeline_span() {
    return {1e-9, true, 1e6, true, "seconds; the clock counts whole picoseconds in 64 bits"};
}
Range coefficient() {
    return {0.0, false, 1.0, true, nullptr};
}

bool inside(const Aabb& inner, const Aabb& outer) {
    return (inner.min.array() >= outer.min.array()).all() &&
           (inner.max.array() <= outer.max.array()).all();
}

bool overlaps(const Aabb& a, const Aabb& b) {  // shared faces do not count
    return (a.min.array() < b.max.array()).all() && (b.min.array() < a.max.array()).all();
}

bool overlaps(const Aabb& box, const Vec3d& center, double radius) {
    const Vec3d closest = center.cwiseMax(box.min).cwiseMin(box.max);
    return (closest - center).squaredNorm() < radius * radius;
}

/// Distance from p into the fluid side of boundary b: positive in the space the fluid may fill,
/// negative inside a solid or outside a container. Height fields and meshes return +inf: the
/// loader does not check against them (the emitter skips candidates next to their particles at
/// run time).
double clearance(const BoundaryDesc& b, const Vec3d& p) {
    switch (b.shape) {
        case BoundaryShape::Container:
            return std::min((p - b.box.min).minCoeff(), (b.box.max - p).minCoeff());
        case BoundaryShape::Box: {  // signed distance to a solid box
            const Vec3d q = (p - 0.5 * (b.box.min + b.box.max)).cwiseAbs() - 0.5 * b.box.extent();
            return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
        }
        case BoundaryShape::Sphere:
            return (p - b.center).norm() - b.radius;
        case BoundaryShape::Cylinder: {  // a 2-D box in (radial, along) coordinates
            const Vec3d d = p - b.center;
            const double along = d.dot(b.axis), radial = (d - along * b.axis).norm();
            const Eigen::Vector2d q(radial - b.radius, std::abs(along - 0.5 * b.height) - 0.5 * b.height);
            return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
        }
        case BoundaryShape::Heightfield:
        case BoundaryShape::Mesh:
            break;
    }
    return std::numeric_limits<double>::infinity();
}

/// A JSON value and its path.
struct Node {
    const json& value;
    std::string path;

    const json* find(const char* key) const {
        const auto it = value.find(key);
        return it == value.end() ? nullptr : &*it;
    }
    Node at(const json& v, const char* key) const { return {v, child(path, key)}; }
};

class Reader {
  public:
    Reader(const std::string& file, const json& doc, std::vector<std::string> cli_paths)
        : m_file(file), m_doc(doc), m_cli(std::move(cli_paths)) {}

    Scene read() const {
        const Node root{m_doc, ""};
        require_object(root, "an object (the scene)");
        check_keys(root, k_top_keys);

        Scene s;
        const json* name = root.find("name");
        if (!name) fail("/name", "nothing", k_name_expected);
        s.name = read_name(root.at(*name, "name"));
        if (const json* d = root.find("description"); d && !d->is_string()) {
            fail("/description", dump(*d), "a string");
        }
        if (const json* v = root.find("simulation")) {
            read_simulation(root.at(*v, "simulation"), s.simulation);
        }
        if (const json* v = root.find("domain")) {
            const Node n = root.at(*v, "domain");
            require_object(n, "an object with min and max");
            check_keys(n, k_box_keys);
            s.domain = read_box(n);
        }
        if (const json* v = root.find("fluid")) read_fluid(root.at(*v, "fluid"), s.fluid);
        if (const json* v = root.find("fluid_blocks")) {
            const Node n = root.at(*v, "fluid_blocks");
            require_array(n, "an array of fluid blocks");
            for (std::size_t i = 0; i < v->size(); ++i) {
                s.fluid_blocks.push_back(read_block({(*v)[i], child(n.path, i)}));
                // DFSPH holds rho0 everywhere (Bender & Koschier 2017): its column at rest is the
                // uncompressed lattice, so its blocks start uncompressed unless a block says so.
                if (s.simulation.method == Method::Dfsph && (*v)[i].is_object() && !(*v)[i].contains("hydrostatic"))
                    s.fluid_blocks.back().hydrostatic = false;
            }
        }
        if (const json* v = root.find("boundaries")) {
            const Node n = root.at(*v, "boundaries");
            require_array(n, "an array of boundaries");
            for (std::size_t i = 0; i < v->size(); ++i) {
                s.boundaries.push_back(read_boundary({(*v)[i], child(n.path, i)}));
            }
        }
        if (const json* v = root.find("output")) read_output(root.at(*v, "output"), s.output);
        const bool wcsph = s.simulation.method == Method::Wcsph, pcisph = s.simulation.method == Method::Pcisph;
        // A section of another method is an error, unless the method was replaced on the command
        // line (`--method dfsph` on a PCISPH scene): the scene's own method's settings are then
        // left unread, as its mode is (read_simulation).
        const bool method_from_cli = from_cli("/simulation/method");
        for (const auto& [key, owner] : {std::pair{"pcisph", Method::Pcisph}, std::pair{"boundary", Method::Pcisph},
                                         std::pair{"dfsph", Method::Dfsph}}) {
            if (const json* v = root.find(key); v && s.simulation.method != owner && !method_from_cli) {
                fail_at(child("", key), dump(*v),
                        std::string("no \"") + key + "\" section: it belongs to method \"" + to_string(owner) +
                            "\", and /simulation/method is \"" + to_string(s.simulation.method) + "\"",
                        {child("", key), "/simulation/method"});
            }
        }
        if (const json* v = root.find("emitters")) {
            const Node n = root.at(*v, "emitters");
            require_array(n, "an array of emitters");
            if (wcsph && !v->empty())
                fail_at(n.path, dump(*v), "no emitters: they are implemented for methods \"pcisph\" and \"dfsph\"",
                        {n.path, "/simulation/method"});
            for (std::size_t i = 0; i < v->size(); ++i) s.emitters.push_back(read_emitter({(*v)[i], child(n.path, i)}));
        }
        // Another method's section (the method replaced on the command line) is still read, into a
        // copy that is dropped: a typo or a bad value in it (or a `--set` into it) is reported,
        // not silently ignored.
        const bool dfsph = s.simulation.method == Method::Dfsph;
        if (const json* v = root.find("pcisph")) {
            auto unused = s.pcisph;
            read_pcisph(root.at(*v, "pcisph"), pcisph ? s.pcisph : unused);
        }
        if (const json* v = root.find("dfsph")) {
            auto unused = s.dfsph;
            read_dfsph(root.at(*v, "dfsph"), dfsph ? s.dfsph : unused);
        }
        if (const json* v = root.find("boundary")) {
            auto unused = s.boundary;
            read_boundary_params(root.at(*v, "boundary"), pcisph ? s.boundary : unused);
        }
        if (!method_takes_support(s.simulation.method, s.fluid.support)) {
            // PCISPH and DFSPH at another support were measured unstable on the resting tank
            // (support 3: PCISPH's velocities 4.5 -> 83 m/s within 5 steps of 0.1 ms, DFSPH a NaN
            // in its first density solve; docs/methods.md, "Known limitations"), so they are refused.
            fail_at("/fluid/support", dump_at("/fluid/support"),
                    "2 or no key: methods \"pcisph\" and \"dfsph\" run with the kernel support of 2 particle "
                    "spacings only (other supports are implemented for method \"wcsph\")",
                    {"/fluid/support", "/simulation/method"});
        }
        if (s.fluid.surface_tension > 0 && wcsph) {
            fail_at("/fluid/surface_tension", dump_at("/fluid/surface_tension"),
                    "0 or no key: surface tension (Becker & Teschner 2007) is implemented for methods "
                    "\"pcisph\" and \"dfsph\" only",
                    {"/fluid/surface_tension", "/simulation/method"});
        }
        if (s.fluid.pressure_gradient == PressureGradient::Corrected && !wcsph) {
            fail_at("/fluid/pressure_gradient", dump_at("/fluid/pressure_gradient"),
                    "\"symmetric\" or no key: the corrected pressure gradient is implemented for method "
                    "\"wcsph\" only (PCISPH and DFSPH have their own pressure solvers)",
                    {"/fluid/pressure_gradient", "/simulation/method"});
        }
        if (s.fluid.density == DensityForm::Continuity && !wcsph) {  // set, not defaulted
            fail_at("/fluid/density", dump_at("/fluid/density"),
                    "\"summation\" or no key: the continuity density is implemented for method \"wcsph\" only",
                    {"/fluid/density", "/simulation/method"});
        }
        if (s.fluid.density_diffusion && density_form(s) != DensityForm::Continuity) {
            fail_at("/fluid/density_diffusion", dump_at("/fluid/density_diffusion"),
                    "no key unless fluid.density is \"continuity\": the summation density is recomputed at every "
                    "evaluation and has nothing to diffuse",
                    {"/fluid/density_diffusion", "/fluid/density"});
        }
        if (s.fluid.wall_pressure && !wcsph) {
            fail_at("/fluid/wall_pressure", dump_at("/fluid/wall_pressure"),
                    "no key: the wall pressure is chosen for method \"wcsph\" only (PCISPH and DFSPH give their "
                    "boundary particles their own pressure)",
                    {"/fluid/wall_pressure", "/simulation/method"});
        }
        if (s.fluid.kinematic_viscosity.value_or(0) > 0 && !wcsph) {
            fail_at("/fluid/kinematic_viscosity", dump_at("/fluid/kinematic_viscosity"),
                    "0 or no key: the laminar viscosity (Morris et al. 1997) is implemented for method \"wcsph\" only",
                    {"/fluid/kinematic_viscosity", "/simulation/method"});
        }
        if (const json* v = root.find("probes")) s.probes = parse_probes(*v, m_file);  // engine/probes.cpp
        if (const json* v = root.find("standing_wave")) s.standing_wave = read_wave(root.at(*v, "standing_wave"), s);

        cross_check(s);
        return s;
    }

  private:
    // -- Failing. The message says "(set on the command line)" when any path involved in the
    // -- error was set or replaced by an override, or holds a value that was.
    bool from_cli(const std::string& path) const {
        return std::any_of(m_cli.begin(), m_cli.end(), [&](const std::string& o) {
            return path == o || path.starts_with(o + "/") ||
                   (!path.empty() && o.starts_with(path + "/"));
        });
    }

    [[noreturn]] void fail_at(const std::string& path, const std::string& found,
                              std::string expected,
                              std::initializer_list<std::string> involved) const {
        if (std::any_of(involved.begin(), involved.end(),
                        [&](const std::string& p) { return from_cli(p); })) {
            expected += " (set on the command line)";
        }
        throw SceneError(m_file, shown(path), found, std::move(expected));
    }

    [[noreturn]] void fail(const std::string& path, const std::string& found,
                           std::string expected) const {
        fail_at(path, found, std::move(expected), {path});
    }

    std::string dump_at(const std::string& path) const {
        const json::json_pointer p(path);
        return m_doc.contains(p) ? dump(m_doc.at(p)) : std::string("nothing");
    }

    // -- Generic readers.
    void require_object(const Node& n, const char* what) const {
        if (!n.value.is_object()) fail(n.path, dump(n.value), what);
    }
    void require_array(const Node& n, const char* what) const {
        if (!n.value.is_array()) fail(n.path, dump(n.value), what);
    }

    void check_keys(const Node& n, std::span<const char* const> keys,
                    const std::string& context = "") const {
        for (const auto& item : n.value.items()) {
            const std::string& key = item.key();
            if (std::none_of(keys.begin(), keys.end(), [&](const char* k) { return key == k; })) {
                fail_at(n.path, "unknown key " + in_quotes(key) + context,
                        "one of: " + join(keys, false) + suggestion(key, keys),
                        {child(n.path, key)});
            }
        }
    }

    double number(const Node& n, const Range& range) const {
        if (!n.value.is_number()) fail(n.path, dump(n.value), range.describe());
        const double x = n.value.get<double>();
        if (!range.contains(x)) fail(n.path, dump(n.value), range.describe());
        return x;
    }

    void read_number(const Node& obj, const char* key, const Range& range, double& out) const {
        if (const json* v = obj.find(key)) out = number(obj.at(*v, key), range);
    }
    void read_number(const Node& obj, const char* key, const Range& range, std::optional<double>& out) const {
        if (const json* v = obj.find(key)) out = number(obj.at(*v, key), range);
    }
    /// A time the clock converts to ticks: positive, then within what the timeline holds.
    void read_time(const Node& obj, const char* key, double& out) const {
        const json* v = obj.find(key);
        if (!v) return;
        const Node node = obj.at(*v, key);
        out = number(node, positive("seconds"));
        if (!timeline_span().contains(out)) fail(node.path, dump(*v), timeline_span().describe());
    }

    Vec3d vec3(const Node& n, const char* unit) const {
        const std::string what = std::string("an array of 3 numbers (") + unit + ")";
        if (!n.value.is_array() || n.value.size() != 3) fail(n.path, dump(n.value), what);
        Vec3d out;
        for (std::size_t i = 0; i < 3; ++i) {
            out[static_cast<Eigen::Index>(i)] =
                number({n.value[i], child(n.path, i)}, any_number(unit));
        }
        return out;
    }

    Vec3d required_vec3(const Node& obj, const char* key, const char* unit) const {
        const json* v = obj.find(key);
        if (!v) {
            fail(child(obj.path, key), "nothing",
                 std::string("an array of 3 numbers (") + unit + ")");
        }
        return vec3(obj.at(*v, key), unit);
    }

    /// Index of the string in `names`, or an error listing them (with a suggestion).
    std::size_t pick(const Node& n, std::span<const char* const> names) const {
        const std::string expected = "one of " + join(names, true);
        if (!n.value.is_string()) fail(n.path, dump(n.value), expected);
        const std::string& s = n.value.get_ref<const std::string&>();
        for (std::size_t i = 0; i < names.size(); ++i) {
            if (s == names[i]) return i;
        }
        fail(n.path, dump(n.value), expected + suggestion(s, names));
    }

    template <class E, std::size_t N>
    E pick_enum(const Node& n, const std::array<E, N>& values) const {
        std::array<const char*, N> names{};
        for (std::size_t i = 0; i < N; ++i) names[i] = to_string(values[i]);
        return values[pick(n, names)];
    }

    // -- Sections.
    std::string read_name(const Node& n) const {
        const char* what = k_name_expected;
        if (!n.value.is_string()) fail(n.path, dump(n.value), what);
        const std::string& s = n.value.get_ref<const std::string&>();
        if (s.empty() || s == "." || s == ".." ||
            s.find_first_of(std::string("/\\\0", 3)) != std::string::npos) {
            fail(n.path, dump(n.value), what);
        }
        return s;
    }

    void read_simulation(const Node& n, SimulationParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_simulation_keys);
        if (const json* v = n.find("method")) p.method = pick_enum(n.at(*v, "method"), k_methods);
        if (p.method != Method::Wcsph) p.stepping.mode = SteppingMode::Adaptive;  // PCISPH's and DFSPH's default
        if (const json* v = n.find("stepping")) read_stepping(n.at(*v, "stepping"), p.stepping);
        // Modes belong to methods: global/individual are WCSPH's (He et al.), adaptive is
        // PCISPH's (Ihmsen et al. 2010); constant is both.
        bool ok = p.stepping.mode == SteppingMode::Constant ||
                  (p.method == Method::Wcsph) != (p.stepping.mode == SteppingMode::Adaptive);
        // `--set simulation.method=dfsph` on a scene written for another method: the scene's
        // mode belongs to the method it replaced, so the new method's default mode is taken
        // (an explicit mode on the command line is still checked).
        const std::string method_path = child(n.path, "method"), mode_path = child(child(n.path, "stepping"), "mode");
        if (!ok && from_cli(method_path) && !from_cli(mode_path)) {
            p.stepping.mode = p.method == Method::Wcsph ? SteppingMode::Global : SteppingMode::Adaptive;
            ok = true;
        }
        if (!ok) {
            fail_at(mode_path, dump_at(mode_path),
                    p.method != Method::Wcsph
                        ? std::string("one of \"constant\", \"adaptive\" for method \"") + to_string(p.method) +
                              "\" (\"global\", \"individual\" and \"binned\" are WCSPH modes)"
                        : std::string("one of \"constant\", \"global\", \"individual\", \"binned\" for method "
                                      "\"wcsph\" (\"adaptive\" is the PCISPH and DFSPH mode: set "
                                      "simulation.method to \"pcisph\" or \"dfsph\")"),
                    {mode_path, method_path});
        }
        read_time(n, "end_time", p.end_time);
        read_number(n, "frame_rate", non_negative("frames per simulated second; 0 writes none"),
                    p.frame_rate);
        read_number(n, "scale", {0.0, false, 1000.0, true, "particle-count multiplier"}, p.scale);
        if (const json* v = n.find("gravity")) p.gravity = vec3(n.at(*v, "gravity"), "m/s^2");
        if (const json* v = n.find("sort_interval")) {
            const Node s = n.at(*v, "sort_interval");
            const char* what = "an integer >= 0 (steps; 0 never re-sorts)";
            if (!v->is_number_integer()) fail(s.path, dump(*v), what);
            const bool in_range = v->is_number_unsigned() ? v->get<std::uint64_t>() <= INT_MAX
                                                          : v->get<std::int64_t>() >= 0 && v->get<std::int64_t>() <= INT_MAX;
            if (!in_range) {
                fail(s.path, dump(*v), what);
            }
            p.sort_interval = v->get<int>();
        }
        if (const json* v = n.find("simd")) {
            if (!v->is_boolean()) fail(child(n.path, "simd"), dump(*v), "true or false");
            p.simd = v->get<bool>();
        }
    }

    void read_stepping(const Node& n, SteppingParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_stepping_keys);
        if (const json* v = n.find("mode")) p.mode = pick_enum(n.at(*v, "mode"), k_modes);
        if (p.mode == SteppingMode::Individual) {
            // He et al. sec. 2.3: half the global coefficients, and no acoustic condition
            // (the published algorithm has none); each can still be set explicitly.
            p.lambda_v = 0.05;
            p.lambda_f = 0.025;
            p.acoustic = false;
        }
        read_time(n, "dt", p.dt);
        read_number(n, "lambda_v", coefficient(), p.lambda_v);
        read_number(n, "lambda_f", coefficient(), p.lambda_f);
        if (const json* v = n.find("acoustic")) {
            if (!v->is_boolean()) fail(child(n.path, "acoustic"), dump(*v), "true or false");
            p.acoustic = v->get<bool>();
        }
        read_number(n, "lambda_c", coefficient(), p.lambda_c);
        if (const json* v = n.find("keep_grid")) {
            if (!v->is_boolean()) fail(child(n.path, "keep_grid"), dump(*v), "true or false");
            p.keep_grid = v->get<bool>();
        }
        read_time(n, "dt_max", p.dt_max);
        read_time(n, "dt_min", p.dt_min);
        if (const json* v = n.find("activation")) p.activation = pick_enum(n.at(*v, "activation"), k_activations);
        if (!(p.dt_min < p.dt_max)) {
            const std::string min_path = child(n.path, "dt_min");
            fail_at(min_path, n.find("dt_min") ? dump(*n.find("dt_min")) : fmt_num(p.dt_min),
                    "a number > 0 and < dt_max = " + fmt_num(p.dt_max) + " (seconds)",
                    {min_path, child(n.path, "dt_max")});
        }
    }

    /// An integer key of `obj` in [lo, hi], if present.
    void read_integer(const Node& obj, const char* key, int lo, int hi, int& out) const {
        const json* v = obj.find(key);
        if (!v) return;
        const std::string what = "an integer from " + std::to_string(lo) + " to " + std::to_string(hi);
        if (!v->is_number_integer()) fail(child(obj.path, key), dump(*v), what);
        const std::int64_t x = v->is_number_unsigned()
                                   ? std::int64_t(std::min<std::uint64_t>(v->get<std::uint64_t>(), INT64_MAX))
                                   : v->get<std::int64_t>();
        if (x < lo || x > hi) fail(child(obj.path, key), dump(*v), what);
        out = int(x);
    }

    void read_pcisph(const Node& n, PcisphParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_pcisph_keys);
        const auto integer = [&](const char* key, int lo, int hi, int& out) { read_integer(n, key, lo, hi, out); };
        integer("iterations", 1, 1000, p.iterations);
        integer("max_iterations", 1, 100000, p.max_iterations);
        if (const json* v = n.find("loop")) p.loop = pick_enum(n.at(*v, "loop"), k_loops);
        read_number(n, "eta", {0.0, false, 0.5, false, "fraction of rest density"}, p.eta);
        if (const json* v = n.find("eta_max")) {
            const Node e = n.at(*v, "eta_max");
            const double x = number(e, {0.0, false, 1.0, false, "fraction of rest density"});
            if (!(x > p.eta)) fail_at(e.path, dump(*v), "a number > eta = " + fmt_num(p.eta), {e.path, child(n.path, "eta")});
            p.eta_max = x;
        }
        const double eta_max = p.eta_max.value_or(10.0 * p.eta);
        if (const json* v = n.find("delta_shock")) {
            const Node d = n.at(*v, "delta_shock");
            const double x = number(d, positive("fraction of rest density"));
            // Ihmsen 2010 after eq. 27: eta_avg < delta_shock < eta_max.
            if (!(x > p.eta && x < eta_max))
                fail_at(d.path, dump(*v),
                        "a number > eta = " + fmt_num(p.eta) + " and < eta_max = " + fmt_computed(eta_max) +
                            " (Ihmsen 2010: eta_avg < delta_shock < eta_max)",
                        {d.path, child(n.path, "eta"), child(n.path, "eta_max")});
            p.delta_shock = x;
        } else if (p.eta_max && !(4.0 * p.eta < *p.eta_max)) {
            // The default delta_shock, 4 eta, must lie below eta_max as a set one must.
            const std::string ep = child(n.path, "eta_max");
            fail_at(ep, dump_at(ep),
                    "a number > 4 eta = " + fmt_computed(4.0 * p.eta) +
                        " (the default delta_shock; Ihmsen 2010: eta_avg < delta_shock < eta_max), or a delta_shock "
                        "between eta and eta_max",
                    {ep, child(n.path, "eta"), child(n.path, "delta_shock")});
        }
        if (p.loop == PcisphLoop::UntilConverged && p.max_iterations < p.iterations) {
            const std::string mp = child(n.path, "max_iterations");
            fail_at(mp, dump_at(mp), "an integer >= iterations = " + std::to_string(p.iterations),
                    {mp, child(n.path, "iterations")});
        }
    }

    void read_dfsph(const Node& n, DfsphParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_dfsph_keys);
        const auto integer = [&](const char* key, int lo, int hi, int& out) { read_integer(n, key, lo, hi, out); };
        const auto boolean = [&](const char* key, bool& out) {
            if (const json* v = n.find(key)) {
                if (!v->is_boolean()) fail(child(n.path, key), dump(*v), "true or false");
                out = v->get<bool>();
            }
        };
        read_number(n, "eta", {0.0, false, 0.5, false, "fraction of rest density"}, p.eta);
        read_number(n, "eta_divergence", {0.0, false, 0.5, false, "fraction of rest density per step"},
                    p.eta_divergence);
        integer("min_iterations", 1, 1000, p.min_iterations);
        integer("max_iterations", 1, 100000, p.max_iterations);
        integer("min_divergence_iterations", 1, 1000, p.min_divergence_iterations);
        integer("max_divergence_iterations", 1, 100000, p.max_divergence_iterations);
        boolean("divergence", p.divergence);
        boolean("warm_start", p.warm_start);
        read_number(n, "relaxation", {0.0, false, 2.0, false, "Jacobi relaxation factor omega"}, p.relaxation);
        read_number(n, "cfl", {0.0, false, 1.0, true, "CFL factor: dt = cfl 2 r / v_max"}, p.cfl);
        for (const auto& [lo, hi] : {std::pair{"min_iterations", "max_iterations"},
                                     std::pair{"min_divergence_iterations", "max_divergence_iterations"}}) {
            const int a = std::string(lo) == "min_iterations" ? p.min_iterations : p.min_divergence_iterations;
            const int b = std::string(lo) == "min_iterations" ? p.max_iterations : p.max_divergence_iterations;
            if (b < a) {
                const std::string mp = child(n.path, hi);
                fail_at(mp, dump_at(mp), std::string("an integer >= ") + lo + " = " + std::to_string(a),
                        {mp, child(n.path, lo)});
            }
        }
    }

    StandingWaveDesc read_wave(const Node& n, const Scene& s) const {
        require_object(n, "an object with amplitude, mode and at");
        check_keys(n, k_wave_keys);
        StandingWaveDesc w;
        w.amplitude = required_number(n, "amplitude", positive("metres"));
        read_integer(n, "mode", 1, 64, w.mode);
        read_number(n, "at", non_negative("seconds: when the wave is given to the fluid"), w.at);
        if (s.simulation.method != Method::Wcsph)
            fail_at(n.path, dump_at(n.path), "no standing_wave: it is given to the fluid of method \"wcsph\" only",
                    {n.path, "/simulation/method"});
        if (s.fluid_blocks.size() != 1)
            fail_at(n.path, dump_at(n.path), "exactly one fluid block, whose box the wave fills (found " +
                    std::to_string(s.fluid_blocks.size()) + ")", {n.path, "/fluid_blocks"});
        const Vec3d g = s.simulation.gravity;
        if (!(g.y() < 0 && g.x() == 0 && g.z() == 0))
            fail_at(n.path, dump_at(n.path), "gravity along -y (the wave's depth is the block's height)",
                    {n.path, "/simulation/gravity"});
        const Aabb& box = s.fluid_blocks.front().box;
        if (!(w.amplitude < 0.25 * (box.max.y() - box.min.y())))
            fail(child(n.path, "amplitude"), dump_at(child(n.path, "amplitude")),
                 "a linear wave: below a quarter of the block's depth " + fmt_num(box.max.y() - box.min.y()) + " m");
        const SteppingMode mode = s.simulation.stepping.mode;
        if (w.at > 0 && mode != SteppingMode::Global && mode != SteppingMode::Constant)
            fail_at(child(n.path, "at"), dump_at(child(n.path, "at")),
                    "0 or no key in stepping mode \"" + std::string(to_string(mode)) +
                        "\": a wave given after the start is set between two steps, which the per-particle modes "
                        "do not share (use \"global\" or \"constant\")",
                    {child(n.path, "at"), "/simulation/stepping/mode"});
        return w;
    }

    EmitterDesc read_emitter(const Node& n) const {
        require_object(n, "an object with position, velocity, radius and rate");
        check_keys(n, k_emitter_keys);
        EmitterDesc e;
        e.position = required_vec3(n, "position", "metres");
        e.velocity = required_vec3(n, "velocity", "m/s");
        if (!(e.velocity.norm() > 0)) {
            const std::string vp = child(n.path, "velocity");
            fail(vp, dump_at(vp), "an array of 3 numbers, not all zero (m/s; its direction is the disc's normal)");
        }
        e.radius = required_number(n, "radius", positive("metres"));
        e.rate = required_number(n, "rate", positive("particles per second"));
        read_number(n, "start", non_negative("seconds"), e.start);
        if (const json* v = n.find("end")) {
            const Node en = n.at(*v, "end");
            e.end = number(en, positive("seconds"));
            if (!(e.end > e.start)) fail_at(en.path, dump(*v), "a time after start = " + fmt_num(e.start) + " (seconds)", {en.path, child(n.path, "start")});
        }
        if (const json* v = n.find("max_particles")) {
            if (!v->is_number_integer() || (!v->is_number_unsigned() && v->get<std::int64_t>() < 1) ||
                (v->is_number_unsigned() && v->get<std::uint64_t>() < 1))
                fail(child(n.path, "max_particles"), dump(*v), "an integer >= 1");
            e.max_particles = v->get<std::uint64_t>();
        }
        return e;
    }

    void read_boundary_params(const Node& n, BoundaryParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_boundary_params_keys);
        if (const json* v = n.find("handling")) p.handling = pick_enum(n.at(*v, "handling"), k_handlings);
        read_number(n, "friction", {0.0, true, 1.0, true, "epsilon of Ihmsen eq. 12; 1 is free slip"}, p.friction);
    }

    void read_fluid(const Node& n, FluidParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_fluid_keys);
        read_number(n, "rest_density", positive("kg/m^3"), p.rest_density);
        read_number(n, "particle_radius", positive("metres"), p.particle_radius);
        read_number(n, "support", {1.5, true, 4.0, true, "kernel support radius in particle spacings"}, p.support);
        read_number(n, "viscosity", non_negative("artificial viscosity alpha"), p.viscosity);
        if (const json* v = n.find("speed_of_sound")) {
            p.speed_of_sound = number(n.at(*v, "speed_of_sound"), positive("m/s"));
        }
        if (const json* v = n.find("boundary_viscosity")) {
            p.boundary_viscosity = number(n.at(*v, "boundary_viscosity"), non_negative("artificial viscosity alpha"));
        }
        read_number(n, "density_fluctuation", {0.0, false, 0.2, true, "fraction of rest density"},
                    p.density_fluctuation);
        read_number(n, "surface_tension", non_negative("m^3/s^2, Becker & Teschner 2007 kappa"),
                    p.surface_tension);
        if (const json* v = n.find("pressure_gradient"))
            p.pressure_gradient = pick_enum(n.at(*v, "pressure_gradient"), k_gradients);
        if (const json* v = n.find("density")) p.density = pick_enum(n.at(*v, "density"), k_density_forms);
        if (const json* v = n.find("density_diffusion"))
            p.density_diffusion = number(n.at(*v, "density_diffusion"),
                                         {0.0, true, 1.0, true, "delta of the delta-SPH diffusion term (0.1 typical)"});
        read_number(n, "kinematic_viscosity", non_negative("m^2/s (water: 1e-6)"), p.kinematic_viscosity);
        if (const json* v = n.find("wall_pressure")) p.wall_pressure = pick_enum(n.at(*v, "wall_pressure"), k_wall_pressures);
    }

    /// @param span_xz only x and z must have max > min (a heightfield's span: its y is ignored).
    Aabb read_box(const Node& n, bool span_xz = false) const {
        Aabb box;
        box.min = required_vec3(n, "min", "metres");
        box.max = required_vec3(n, "max", "metres");
        const bool ok = span_xz ? box.min.x() < box.max.x() && box.min.z() < box.max.z()
                                : (box.min.array() < box.max.array()).all();
        if (!ok) {
            const std::string max_path = child(n.path, "max");
            fail_at(max_path, dump_at(max_path),
                    "a point above min " + fmt_vec(box.min) + (span_xz ? " in x and z (metres; y is ignored)" : " on every axis (metres)"),
                    {max_path, child(n.path, "min")});
        }
        return box;
    }

    FluidBlock read_block(const Node& n) const {
        require_object(n, "an object with min, max and optionally velocity");
        check_keys(n, k_block_keys);
        FluidBlock b;
        b.box = read_box(n);
        if (const json* v = n.find("velocity")) b.velocity = vec3(n.at(*v, "velocity"), "m/s");
        if (const json* v = n.find("hydrostatic")) {
            if (!v->is_boolean()) fail(child(n.path, "hydrostatic"), dump(*v), "true or false");
            b.hydrostatic = v->get<bool>();
        }
        return b;
    }

    BoundaryDesc read_boundary(const Node& n) const {
        require_object(n, "an object with a type");
        BoundaryDesc b;
        const json* type = n.find("type");
        if (!type) {
            std::array<const char*, k_shapes.size()> names{};
            for (std::size_t i = 0; i < names.size(); ++i) names[i] = to_string(k_shapes[i]);
            fail(child(n.path, "type"), "nothing", "one of " + join(names, true));
        }
        b.shape = pick_enum(n.at(*type, "type"), k_shapes);
        const std::string context = " for a " + in_quotes(to_string(b.shape)) + " boundary";
        if (b.shape == BoundaryShape::Sphere) {
            check_keys(n, k_sphere_boundary_keys, context);
            b.center = required_vec3(n, "center", "metres");
            const json* r = n.find("radius");
            if (!r) fail(child(n.path, "radius"), "nothing", positive("metres").describe());
            b.radius = number(n.at(*r, "radius"), positive("metres"));
        } else if (b.shape == BoundaryShape::Cylinder) {
            check_keys(n, k_cylinder_boundary_keys, context);
            b.center = required_vec3(n, "center", "metres");
            b.axis = direction(n, "axis");
            b.radius = required_number(n, "radius", positive("metres"));
            b.height = required_number(n, "height", positive("metres"));
            b.box = cylinder_box(b);
        } else if (b.shape == BoundaryShape::Heightfield) {
            check_keys(n, k_heightfield_boundary_keys, context);
            const Aabb span = read_box(n, true);
            const char* what = "an array of at least 2 rows (along z), each an array of the same number (>= 2) of "
                               "heights (metres, along x)";
            const json* hv = n.find("heights");
            if (!hv) fail(child(n.path, "heights"), "nothing", what);
            const Node hn = n.at(*hv, "heights");
            if (!hv->is_array() || hv->size() < 2) fail(hn.path, dump(*hv), what);
            for (std::size_t k = 0; k < hv->size(); ++k) {
                const Node row{(*hv)[k], child(hn.path, k)};
                if (!row.value.is_array() || row.value.size() < 2 ||
                    (k > 0 && row.value.size() != b.heights[0].size()))
                    fail(row.path, dump(row.value), what);
                std::vector<double> r;
                for (std::size_t i = 0; i < row.value.size(); ++i)
                    r.push_back(number({row.value[i], child(row.path, i)}, any_number("metres")));
                b.heights.push_back(std::move(r));
            }
            heightfield_triangles(span, b);
        } else if (b.shape == BoundaryShape::Mesh) {
            check_keys(n, k_mesh_boundary_keys, context);
            const json* f = n.find("file");
            const char* what = "a path to a Wavefront OBJ file (relative to the scene file)";
            const json* inline_vertices = n.find("vertices");
            for (const char* key : {"vertices", "triangles"})
                if (const json* v = n.find(key); f && v)
                    fail_at(child(n.path, key), dump(*v),
                            std::string("no ") + key + " beside a file: a mesh is an OBJ file or vertices and triangles",
                            {child(n.path, key), child(n.path, "file")});
            if (!f && !inline_vertices)
                fail(child(n.path, "file"), "nothing", std::string(what) + ", or vertices and triangles");
            double scale = 1.0;
            read_number(n, "scale", positive("factor applied to the OBJ coordinates"), scale);
            Vec3d translate = Vec3d::Zero();
            if (const json* t = n.find("translate")) translate = vec3(n.at(*t, "translate"), "metres");
            if (f) {
                if (!f->is_string() || f->get<std::string>().empty()) fail(child(n.path, "file"), dump(*f), what);
                std::filesystem::path path = f->get<std::string>();
                if (path.is_relative()) path = std::filesystem::path(m_file).parent_path() / path;
                if (!std::filesystem::is_regular_file(path))
                    fail(child(n.path, "file"), dump(*f), std::string(what) + "; there is no such file in the scene file's folder");
                b.file = path;
                try {
                    read_obj(path, b.vertices, b.triangles, f->get<std::string>());
                } catch (const InputError& e) {  // a corrupt file: name it as the scene does
                    fail(child(n.path, "file"), dump(*f), std::string(what) + "; " + e.what());
                }
                if (b.triangles.empty())
                    fail(child(n.path, "file"), dump(*f), std::string(what) + " with at least one face (f line)");
            } else {
                read_inline_mesh(n, b);
            }
            for (auto& v : b.vertices) v = scale * v + translate;
            b.box = vertices_box(b.vertices);
        } else {
            check_keys(n, k_boxlike_boundary_keys, context);
            b.box = read_box(n);
        }
        if (const json* v = n.find("motion")) b.motion = read_motion(n.at(*v, "motion"), b);
        return b;
    }

    /// A mesh given in the scene, with the rules of an OBJ file: `vertices`, points (metres), and
    /// `triangles`, at least one triple of vertex indices (0-based), each below the vertex count.
    void read_inline_mesh(const Node& n, BoundaryDesc& b) const {
        const json& v = *n.find("vertices");
        const Node vn = n.at(v, "vertices");
        if (!v.is_array() || v.empty()) fail(vn.path, dump(v), "an array of points, each an array of 3 numbers (metres)");
        for (std::size_t i = 0; i < v.size(); ++i) b.vertices.push_back(vec3({v[i], child(vn.path, i)}, "metres"));
        const std::string what = "an array of at least one triangle, each an array of 3 vertex indices from 0 to " +
                                 std::to_string(v.size() - 1);
        const json* t = n.find("triangles");
        if (!t) fail(child(n.path, "triangles"), "nothing", what);
        const Node tn = n.at(*t, "triangles");
        if (!t->is_array() || t->empty()) fail(tn.path, dump(*t), what);
        for (std::size_t k = 0; k < t->size(); ++k) {
            const Node e{(*t)[k], child(tn.path, k)};
            if (!e.value.is_array() || e.value.size() != 3) fail(e.path, dump(e.value), what);
            std::array<int, 3> tri{};
            for (std::size_t c = 0; c < 3; ++c) {
                const json& x = e.value[c];
                if (!x.is_number_integer() || (!x.is_number_unsigned() && x.get<std::int64_t>() < 0) ||
                    x.get<std::uint64_t>() >= v.size())
                    fail(child(e.path, c), dump(x), what);
                tri[c] = int(x.get<std::uint64_t>());
            }
            b.triangles.push_back(tri);
        }
    }

    double required_number(const Node& obj, const char* key, const Range& range) const {
        const json* v = obj.find(key);
        if (!v) fail(child(obj.path, key), "nothing", range.describe());
        return number(obj.at(*v, key), range);
    }

    /// A direction: any non-zero vector, returned normalised.
    Vec3d direction(const Node& obj, const char* key) const {
        const char* what = "an array of 3 numbers, not all zero (a direction; it is normalised)";
        const json* v = obj.find(key);
        if (!v) fail(child(obj.path, key), "nothing", what);
        const Node a = obj.at(*v, key);
        const Vec3d d = vec3(a, "a direction; it is normalised");
        if (!(d.norm() > 0) || !std::isfinite(d.norm())) fail(a.path, dump(a.value), what);
        return unit(d);
    }

    /// A kinematic motion (engine/motion.hpp); `body` is the boundary it moves (a circle
    /// carries the body's centre round it, so that centre must lie on the circle).
    Motion read_motion(const Node& n, const BoundaryDesc& body) const {
        require_object(n, "an object with a type (a motion)");
        std::array<const char*, k_motion_types.size()> names{};
        for (std::size_t i = 0; i < names.size(); ++i) names[i] = to_string(k_motion_types[i]);
        const json* type = n.find("type");
        if (!type) fail(child(n.path, "type"), "nothing", "one of " + join(names, true));
        Motion m;
        m.type = pick_enum(n.at(*type, "type"), k_motion_types);
        const std::string context = " for a " + in_quotes(to_string(m.type)) + " motion";
        switch (m.type) {
            case MotionType::Linear:
                check_keys(n, k_linear_motion_keys, context);
                m.velocity = required_vec3(n, "velocity", "m/s");
                break;
            case MotionType::Sinusoidal:
                check_keys(n, k_sinusoidal_motion_keys, context);
                m.axis = direction(n, "axis");
                m.amplitude = required_number(n, "amplitude", positive("metres"));
                m.period = required_number(n, "period", positive("seconds"));
                read_number(n, "phase", any_number("radians"), m.phase);
                break;
            case MotionType::Path: {
                check_keys(n, k_path_motion_keys, context);
                const char* what = "an array of at least 2 points, each an array of 3 numbers (metres)";
                const json* v = n.find("points");
                if (!v) fail(child(n.path, "points"), "nothing", what);
                const Node pts = n.at(*v, "points");
                if (!v->is_array() || v->size() < 2) fail(pts.path, dump(*v), what);
                for (std::size_t i = 0; i < v->size(); ++i) {
                    const Node e{(*v)[i], child(pts.path, i)};
                    const Vec3d p = vec3(e, "metres");
                    if (i > 0 && p == m.points.back()) {
                        fail(e.path, dump(e.value),
                             "a point different from the previous one " + fmt_vec(m.points.back()) +
                                 " (metres)");
                    }
                    m.points.push_back(p);
                }
                m.speed = required_number(n, "speed", positive("m/s along the path"));
                if (const json* l = n.find("loop")) {
                    if (!l->is_boolean()) fail(child(n.path, "loop"), dump(*l), "true or false");
                    m.loop = l->get<bool>();
                }
                break;
            }
            case MotionType::Circle: {
                check_keys(n, k_circle_motion_keys, context);
                m.center = required_vec3(n, "center", "metres");
                m.radius = required_number(n, "radius", positive("metres"));
                m.axis = direction(n, "axis");
                m.speed = required_number(n, "speed", positive("m/s along the circle"));
                // The body is translated round the circle: its centre must start on it.
                const Vec3d rel = reference_point(body) - m.center;
                const Vec3d in_plane = rel - rel.dot(m.axis) * m.axis;
                const double distance = in_plane.norm();
                if (std::abs(distance - m.radius) > 1e-6 * std::max(1.0, m.radius) || !(distance > 0)) {
                    const std::string radius_path = child(n.path, "radius");
                    fail_at(radius_path, dump_at(radius_path),
                            "the distance from center to the boundary's centre " +
                                fmt_vec(reference_point(body)) + " in the circle's plane, " +
                                fmt_computed(distance) +
                                " (metres; the boundary is carried round the circle from where it "
                                "is declared)",
                            {radius_path, child(n.path, "center"), child(n.path, "axis")});
                }
                m.start = in_plane / distance;
                break;
            }
        }
        return m;
    }

    void read_output(const Node& n, OutputParams& p) const {
        require_object(n, "an object");
        check_keys(n, k_output_keys);
        if (const json* v = n.find("format")) {
            // One format name, or an array of them (each at most once).
            const Node f = n.at(*v, "format");
            std::array<const char*, k_formats.size()> names{};
            for (std::size_t i = 0; i < names.size(); ++i) names[i] = to_string(k_formats[i]);
            p.formats.clear();
            if (v->is_array()) {
                if (v->empty()) {
                    fail(f.path, dump(*v), "a format or a non-empty array of formats, each one of " +
                                               join(names, true));
                }
                for (std::size_t i = 0; i < v->size(); ++i) {
                    const Node e{(*v)[i], child(f.path, i)};
                    const FrameFormat ff = pick_enum(e, k_formats);
                    if (std::find(p.formats.begin(), p.formats.end(), ff) != p.formats.end()) {
                        fail(e.path, dump(e.value), "each format at most once");
                    }
                    p.formats.push_back(ff);
                }
            } else {
                p.formats.push_back(pick_enum(f, k_formats));
            }
        }
        if (const json* v = n.find("surface")) {
            const Node sn = n.at(*v, "surface");
            require_object(sn, "an object");
            check_keys(sn, k_surface_keys);
            const auto read = [&](const char* key, const Range& range, std::optional<double>& out) {
                if (const json* x = sn.find(key)) out = number(sn.at(*x, key), range);
            };
            read("voxel_size", positive("metres"), p.surface.voxel_size);
            read("sphere_radius", positive("metres"), p.surface.sphere_radius);
            read("smoothing", non_negative("metres, the Gaussian filter's width; 0 smooths nothing"),
                 p.surface.smoothing);
            if (const json* x = sn.find("keep_volume")) {
                if (!x->is_boolean()) fail(child(sn.path, "keep_volume"), dump(*x), "true or false");
                p.surface.keep_volume = x->get<bool>();
            }
        }
        if (const json* v = n.find("attributes")) {
            const Node a = n.at(*v, "attributes");
            require_array(a,
                          ("an array of strings, each one of " + join(k_attributes, true)).c_str());
            p.attributes.clear();
            p.attributes_explicit = true;
            for (std::size_t i = 0; i < v->size(); ++i) {
                const Node e{(*v)[i], child(a.path, i)};
                const char* name = k_attributes[pick(e, k_attributes)];
                if (std::find(p.attributes.begin(), p.attributes.end(), name) !=
                    p.attributes.end()) {
                    fail(e.path, dump(e.value), "each attribute at most once");
                }
                p.attributes.emplace_back(name);
            }
        }
    }

    // -- Checks across sections, on the parsed values.
    void cross_check(const Scene& s) const {
        if (s.fluid_blocks.empty() && s.emitters.empty()) {
            fail("/fluid_blocks", dump_at("/fluid_blocks"),
                 "at least one fluid block or emitter (otherwise the scene would "
                 "simulate nothing)");
        }
        const double spacing = 2.0 * s.particle_radius();
        const std::string radius_path = "/fluid/particle_radius", scale_path = "/simulation/scale";
        check_surface(s);
        // A moving boundary is checked where it is at t = 0 (a sinusoid with a phase starts
        // displaced); every other motion starts at its declared geometry.
        std::vector<BoundaryDesc> at_start;
        std::vector<bool> shifted;
        for (const BoundaryDesc& declared : s.boundaries) {
            const Vec3d d0 = declared.motion ? displacement(*declared.motion, 0.0) : Vec3d::Zero();
            at_start.push_back(declared.motion ? translated(declared, d0) : declared);
            shifted.push_back(d0 != Vec3d::Zero());
        }
        // A pressure probe outside the domain reads nothing (0 at every sample).
        const Aabb domain = s.domain ? *s.domain : default_domain(s, s.fluid.support * spacing);
        for (std::size_t k = 0; k < s.probes.size(); ++k) {
            if (s.probes[k].type != ProbeType::Pressure || domain.contains(s.probes[k].point)) continue;
            const std::string ppath = child(child("/probes", k), "point");
            const auto vec = [&](const Vec3d& v) { return s.domain ? fmt_vec(v) : fmt_vec_computed(v); };
            const std::string expected = "a point inside the domain (min " + vec(domain.min) + ", max " +
                                         vec(domain.max) + (s.domain ? ")" : ": the boundaries and fluid grown by h)");
            if (s.domain) fail_at(ppath, dump_at(ppath), expected, {ppath, "/domain"});
            fail_at(ppath, dump_at(ppath), expected, {ppath});
        }
        // A container reaching beyond the domain lets the fluid leave the domain (and stop the
        // run) before it meets the container's walls.
        for (std::size_t j = 0; s.domain && j < at_start.size(); ++j) {
            const BoundaryDesc& b = at_start[j];
            if (b.shape != BoundaryShape::Container || inside(b.box, *s.domain)) continue;
            const std::string bpath = child("/boundaries", j);
            fail_at(bpath, dump_at(bpath),
                    "a container inside the domain (min " + fmt_vec(s.domain->min) + ", max " + fmt_vec(s.domain->max) +
                        "): fluid would leave the domain before it meets the container's walls",
                    {bpath, "/domain"});
        }
        for (std::size_t i = 0; i < s.fluid_blocks.size(); ++i) {
            const Aabb& box = s.fluid_blocks[i].box;
            const std::string path = child("/fluid_blocks", i);
            if (s.domain && !inside(box, *s.domain)) {
                fail_at(path, dump_at(path),
                        "a block inside the domain (min " + fmt_vec(s.domain->min) + ", max " +
                            fmt_vec(s.domain->max) + ")",
                        {path, "/domain"});
            }
            for (std::size_t j = 0; j < at_start.size(); ++j) {
                const BoundaryDesc& b = at_start[j];
                const auto vec = [&](const Vec3d& v) { return shifted[j] ? fmt_vec_computed(v) : fmt_vec(v); };
                const std::string bpath = child("/boundaries", j) + (shifted[j] ? " at t = 0" : "");
                const std::string where = " " + bpath + " (min " + vec(b.box.min) + ", max " +
                                          vec(b.box.max) + ")";
                if (b.shape == BoundaryShape::Container && !inside(box, b.box)) {
                    fail_at(path, dump_at(path), "a block inside the container" + where,
                            {path, child("/boundaries", j)});
                }
                if (b.shape == BoundaryShape::Box && overlaps(box, b.box)) {
                    fail_at(path, dump_at(path), "a block clear of the box obstacle" + where,
                            {path, child("/boundaries", j)});
                }
                if (b.shape == BoundaryShape::Sphere && overlaps(box, b.center, b.radius)) {
                    fail_at(path, dump_at(path),
                            "a block clear of the sphere " + bpath + " (center " +
                                vec(b.center) + ", radius " + fmt_num(b.radius) + ")",
                            {path, child("/boundaries", j)});
                }
            }
            for (std::size_t j = 0; j < i; ++j) {  // two lattices in one place: coincident particles
                const Aabb& other = s.fluid_blocks[j].box;
                if (overlaps(box, other)) {
                    const std::string opath = child("/fluid_blocks", j);
                    fail_at(path, dump_at(path),
                            "a block clear of " + opath + " (min " + fmt_vec(other.min) + ", max " + fmt_vec(other.max) +
                                "): overlapping blocks put particles on top of each other; sharing a face is fine",
                            {path, opath});
                }
            }
            if (lattice_cells(box, spacing).minCoeff() < 1.0) {
                fail_at(path, dump_at(path),
                        "a block at least " + fmt_computed(spacing) +
                            " m thick on every axis, to hold one particle (spacing = 2 x "
                            "particle radius after scale)",
                        {path, radius_path, scale_path});
            }
        }

        for (std::size_t i = 0; i < s.emitters.size(); ++i) check_emitter(s, at_start, i, spacing);

    }

    /// An emitter's disc (its candidate lattice, emitter_system.cpp) and the two particle layers
    /// in front of it along its velocity, 2 x spacing, must lie in the domain and on the fluid
    /// side of every container, box, sphere and cylinder at t = 0: otherwise candidates sit in a
    /// wall, or the emitter points into one and the first layers have nowhere to go.
    void check_emitter(const Scene& s, const std::vector<BoundaryDesc>& at_start, std::size_t i,
                       double spacing) const {
        const EmitterDesc& em = s.emitters[i];
        const std::string path = child("/emitters", i), radius_path = "/fluid/particle_radius";
        const Vec3d n = em.velocity.normalized();
        const std::vector<Vec3d> disc = emitter_disc(em, spacing);
        const double ahead = 2.0 * spacing;
        for (int layer = 0; layer <= 4; ++layer) {
            const double off = ahead * layer / 4.0;
            for (const Vec3d& on_disc : disc) {
                const Vec3d p = on_disc + off * n;
                const std::string at = (layer == 0 ? "the disc point " : "the point ") + fmt_vec_computed(p);
                if (s.domain && !s.domain->contains(p)) {
                    fail_at(path, dump_at(path),
                            layer == 0 ? "an emitter disc inside the domain (min " + fmt_vec(s.domain->min) +
                                             ", max " + fmt_vec(s.domain->max) + "); " + at + " is outside"
                                       : "an emitter that does not point out of the domain (min " +
                                             fmt_vec(s.domain->min) + ", max " + fmt_vec(s.domain->max) + "): " + at +
                                             ", " + fmt_computed(off) +
                                             " m in front of the disc along its velocity, is outside",
                            {path, "/domain"});
                }
                for (std::size_t b = 0; b < at_start.size(); ++b) {
                    if (clearance(at_start[b], p) > 0.0) continue;
                    const std::string bpath = child("/boundaries", b);
                    const std::string shape = std::string(to_string(at_start[b].shape)) + " " + bpath;
                    const bool container = at_start[b].shape == BoundaryShape::Container;
                    fail_at(path, dump_at(path),
                            layer == 0 ? "an emitter disc on the fluid side of every boundary; " + at +
                                             (container ? " is outside the " : " is inside the ") + shape
                                       : "an emitter that does not point into a wall: the first two layers it "
                                         "emits fill the " + fmt_computed(ahead) +
                                             " m (2 x spacing) in front of its disc, and " + at + ", " +
                                             fmt_computed(off) + " m along its velocity, is beyond the wall of the " +
                                             shape,
                            {path, bpath, radius_path});
                }
            }
        }
    }

    // The surface's sizes against the particle radius r (after scale): a voxel of at least r/8
    // (the level set's memory grows as its inverse square), a sphere of at least r and 1.5
    // voxels (OpenVDB's rasteriser skips smaller ones), a filter at most 4 spheres wide.
    void check_surface(const Scene& s) const {
        const double r = s.particle_radius();
        const SurfaceParams::Resolved v = s.output.surface.resolve(r);
        const std::string base = "/output/surface/", radius_path = "/fluid/particle_radius",
                          scale_path = "/simulation/scale";
        const auto at = [&](const char* key) { return base + key; };
        if (v.voxel_size < r / 8) {
            fail_at(at("voxel_size"), fmt_computed(v.voxel_size),
                    "a voxel of at least the particle radius / 8 = " + fmt_computed(r / 8) + " m",
                    {at("voxel_size"), radius_path, scale_path});
        }
        if (v.sphere_radius < std::max(r, 1.5 * v.voxel_size)) {
            fail_at(at("sphere_radius"), fmt_computed(v.sphere_radius),
                    "a sphere radius of at least the particle radius and 1.5 voxels = " +
                        fmt_computed(std::max(r, 1.5 * v.voxel_size)) + " m",
                    {at("sphere_radius"), at("voxel_size"), radius_path, scale_path});
        }
        if (v.smoothing > 4 * v.sphere_radius) {
            fail_at(at("smoothing"), fmt_computed(v.smoothing),
                    "a filter at most 4 sphere radii = " + fmt_computed(4 * v.sphere_radius) + " m wide",
                    {at("smoothing"), at("sphere_radius"), radius_path, scale_path});
        }
    }

    const std::string& m_file;
    const json& m_doc;
    std::vector<std::string> m_cli;
};


}  // namespace

std::vector<std::string> method_names() {
    std::vector<std::string> out;
    for (const Method m : k_methods) out.emplace_back(to_string(m));
    return out;
}

std::vector<std::string> stepping_mode_names() {
    std::vector<std::string> out;
    for (const SteppingMode m : k_modes) out.emplace_back(to_string(m));
    return out;
}

Scene parse_scene(const std::string& text, const std::string& file,
                  const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
    json doc = parse_document(text, file);
    std::vector<std::string> cli_paths;
    for (const auto& [pointer, value] : overrides) {
        cli_paths.push_back(apply_override(doc, pointer_tokens(pointer, file), value, file));
    }
    return Reader(file, doc, std::move(cli_paths)).read();
}

BoundaryDesc cylinder_boundary(const Vec3d& center, const Vec3d& axis, double radius, double height) {
    BoundaryDesc b;
    b.shape = BoundaryShape::Cylinder;
    b.center = center;
    b.axis = axis.squaredNorm() > 0 ? unit(axis) : axis;  // a zero axis is left for validate_scene to name
    b.radius = radius;
    b.height = height;
    b.box = cylinder_box(b);
    return b;
}

BoundaryDesc heightfield_boundary(const Aabb& span, std::vector<std::vector<double>> heights) {
    BoundaryDesc b;
    b.shape = BoundaryShape::Heightfield;
    b.heights = std::move(heights);
    b.box = span;
    const bool grid = b.heights.size() >= 2 && b.heights[0].size() >= 2 &&
                      std::all_of(b.heights.begin(), b.heights.end(), [&](const auto& r) { return r.size() == b.heights[0].size(); });
    if (grid) heightfield_triangles(span, b);  // otherwise validate_scene names the heights
    return b;
}

BoundaryDesc mesh_boundary(std::vector<Vec3d> vertices, std::vector<std::array<int, 3>> triangles) {
    BoundaryDesc b;
    b.shape = BoundaryShape::Mesh;
    b.vertices = std::move(vertices);
    b.triangles = std::move(triangles);
    b.box = vertices_box(b.vertices);
    return b;
}

}  // namespace sph
