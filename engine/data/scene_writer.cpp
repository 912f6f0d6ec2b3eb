/// @file
/// @brief A Scene as the scene file that loads back into it (scene_to_json), and the loader's
/// checks for a scene built or changed in code (validate_scene): the scene written out and read
/// back by parse_scene, so that one set of rules, with one set of messages, covers both.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "engine/core/errors.hpp"
#include "engine/data/scene.hpp"
#include "engine/data/scene_detail.hpp"

namespace sph {

namespace {

using json = nlohmann::json;

json vec(const Vec3d& v) {
    return json::array({v.x(), v.y(), v.z()});
}

json box(const Aabb& b) {
    return json{{"min", vec(b.min)}, {"max", vec(b.max)}};
}

json motion_json(const Motion& m) {
    json j{{"type", to_string(m.type)}};
    switch (m.type) {
        case MotionType::Linear:
            j["velocity"] = vec(m.velocity);
            break;
        case MotionType::Sinusoidal:
            j["axis"] = vec(m.axis);
            j["amplitude"] = m.amplitude;
            j["period"] = m.period;
            j["phase"] = m.phase;
            break;
        case MotionType::Path: {
            json pts = json::array();
            for (const Vec3d& p : m.points) pts.push_back(vec(p));
            j["points"] = std::move(pts);
            j["speed"] = m.speed;
            j["loop"] = m.loop;
            break;
        }
        case MotionType::Circle:  // `start` is derived from the body's position, as the loader does
            j["center"] = vec(m.center);
            j["radius"] = m.radius;
            j["axis"] = vec(m.axis);
            j["speed"] = m.speed;
            break;
    }
    return j;
}

json boundary_json(const BoundaryDesc& b) {
    json j{{"type", to_string(b.shape)}};
    switch (b.shape) {
        case BoundaryShape::Container:
        case BoundaryShape::Box:
            j.update(box(b.box));
            break;
        case BoundaryShape::Sphere:
            j["center"] = vec(b.center);
            j["radius"] = b.radius;
            break;
        case BoundaryShape::Cylinder:
            j["center"] = vec(b.center);
            j["axis"] = vec(b.axis);
            j["radius"] = b.radius;
            j["height"] = b.height;
            break;
        case BoundaryShape::Heightfield:
            j.update(box(b.box));
            j["heights"] = b.heights;
            break;
        case BoundaryShape::Mesh: {  // inline: exact whatever file, scale and offset it came from
            json v = json::array(), t = json::array();
            for (const Vec3d& p : b.vertices) v.push_back(vec(p));
            for (const auto& f : b.triangles) t.push_back(json::array({f[0], f[1], f[2]}));
            j["vertices"] = std::move(v);
            j["triangles"] = std::move(t);
            break;
        }
    }
    if (b.motion) j["motion"] = motion_json(*b.motion);
    return j;
}

json probe_json(const ProbeDesc& d) {
    json j{{"type", to_string(d.type)}, {"name", d.name}, {"rate", d.rate}};
    switch (d.type) {
        case ProbeType::Pressure:
            j["point"] = vec(d.point);
            j["source"] = to_string(d.source);
            if (d.source == PressureSource::Boundary && d.radius != 0) j["radius"] = d.radius;  // 0: the default
            if (d.source == PressureSource::Sensor) j["diameter"] = d.diameter, j["normal"] = vec(d.normal);
            break;
        case ProbeType::Height:
            j["from"] = vec(d.from);
            j["to"] = vec(d.to);
            j["method"] = to_string(d.height_method);
            break;
        case ProbeType::Front:
            j["method"] = to_string(d.method);
            if (d.method == FrontMethod::Neighbours) {
                j["direction"] = vec(d.direction);
                j["min_neighbours"] = d.min_neighbours;
            } else {
                j["from"] = vec(d.from);
                j["to"] = vec(d.to);
            }
            break;
        case ProbeType::Fluid:
            break;
    }
    if (d.experiment) {
        const ProbeExperiment& e = *d.experiment;
        json x{{"file", e.file},           {"t_scale", e.t_scale},     {"value_scale", e.value_scale},
               {"value_offset", e.value_offset}, {"max_shift", e.max_shift}};
        if (e.t_min != ProbeExperiment{}.t_min || e.t_max != ProbeExperiment{}.t_max)
            x["t_range"] = json::array({e.t_min, e.t_max});
        j["experiment"] = std::move(x);
    }
    return j;
}

}  // namespace

nlohmann::json scene_to_json(const Scene& s) {
    json j;
    j["name"] = s.name;

    const SimulationParams& sim = s.simulation;
    const SteppingParams& st = sim.stepping;
    json stepping{{"mode", to_string(st.mode)},         {"dt", st.dt},           {"lambda_v", st.lambda_v},
                  {"lambda_f", st.lambda_f},            {"acoustic", st.acoustic}, {"lambda_c", st.lambda_c},
                  {"dt_max", st.dt_max},                {"dt_min", st.dt_min},   {"activation", to_string(st.activation)},
                  {"keep_grid", st.keep_grid}};
    j["simulation"] = json{{"method", to_string(sim.method)}, {"stepping", std::move(stepping)},
                           {"end_time", sim.end_time},        {"frame_rate", sim.frame_rate},
                           {"scale", sim.scale},              {"gravity", vec(sim.gravity)},
                           {"sort_interval", sim.sort_interval}, {"simd", sim.simd}};
    if (s.domain) j["domain"] = box(*s.domain);

    const FluidParams& f = s.fluid;
    json fluid{{"rest_density", f.rest_density},
               {"particle_radius", f.particle_radius},
               {"support", f.support},
               {"density_fluctuation", f.density_fluctuation},
               {"surface_tension", f.surface_tension},
               {"pressure_gradient", to_string(f.pressure_gradient)}};
    if (f.viscosity) fluid["viscosity"] = *f.viscosity;
    if (f.speed_of_sound) fluid["speed_of_sound"] = *f.speed_of_sound;
    if (f.boundary_viscosity) fluid["boundary_viscosity"] = *f.boundary_viscosity;
    if (f.density) fluid["density"] = to_string(*f.density);
    if (f.density_diffusion) fluid["density_diffusion"] = *f.density_diffusion;
    if (f.kinematic_viscosity) fluid["kinematic_viscosity"] = *f.kinematic_viscosity;
    if (f.wall_pressure) fluid["wall_pressure"] = to_string(*f.wall_pressure);
    j["fluid"] = std::move(fluid);

    json blocks = json::array();
    for (const FluidBlock& b : s.fluid_blocks) {
        json block = box(b.box);
        block["velocity"] = vec(b.velocity);
        block["hydrostatic"] = b.hydrostatic;
        blocks.push_back(std::move(block));
    }
    j["fluid_blocks"] = std::move(blocks);
    json boundaries = json::array();
    for (const BoundaryDesc& b : s.boundaries) boundaries.push_back(boundary_json(b));
    j["boundaries"] = std::move(boundaries);

    if (!s.emitters.empty()) {
        json emitters = json::array();
        for (const EmitterDesc& e : s.emitters) {
            json em{{"position", vec(e.position)}, {"velocity", vec(e.velocity)}, {"radius", e.radius},
                    {"rate", e.rate},              {"start", e.start}};
            // +inf, no end: emits to the run's end; anything else (NaN too) is checked
            if (e.end != std::numeric_limits<double>::infinity()) em["end"] = e.end;
            if (e.max_particles != std::numeric_limits<std::uint64_t>::max()) em["max_particles"] = e.max_particles;
            emitters.push_back(std::move(em));
        }
        j["emitters"] = std::move(emitters);
    }

    const OutputParams& o = s.output;
    json formats = json::array();
    for (FrameFormat ff : o.formats) formats.push_back(to_string(ff));
    json output{{"format", std::move(formats)}};
    json surface{{"keep_volume", o.surface.keep_volume}};
    if (o.surface.voxel_size) surface["voxel_size"] = *o.surface.voxel_size;
    if (o.surface.sphere_radius) surface["sphere_radius"] = *o.surface.sphere_radius;
    if (o.surface.smoothing) surface["smoothing"] = *o.surface.smoothing;
    output["surface"] = std::move(surface);
    if (o.attributes_explicit || o.attributes != OutputParams{}.attributes) output["attributes"] = o.attributes;
    j["output"] = std::move(output);

    // A method's own sections only: the loader refuses another method's.
    if (sim.method == Method::Pcisph) {
        const PcisphParams& p = s.pcisph;
        json pc{{"iterations", p.iterations},
                {"max_iterations", p.max_iterations},
                {"loop", to_string(p.loop)},
                {"eta", p.eta}};
        if (p.eta_max) pc["eta_max"] = *p.eta_max;
        if (p.delta_shock) pc["delta_shock"] = *p.delta_shock;
        j["pcisph"] = std::move(pc);
        j["boundary"] = json{{"handling", to_string(s.boundary.handling)}, {"friction", s.boundary.friction}};
    }
    if (sim.method == Method::Dfsph) {
        const DfsphParams& d = s.dfsph;
        j["dfsph"] = json{{"eta", d.eta},
                          {"eta_divergence", d.eta_divergence},
                          {"min_iterations", d.min_iterations},
                          {"max_iterations", d.max_iterations},
                          {"min_divergence_iterations", d.min_divergence_iterations},
                          {"max_divergence_iterations", d.max_divergence_iterations},
                          {"divergence", d.divergence},
                          {"warm_start", d.warm_start},
                          {"relaxation", d.relaxation},
                          {"cfl", d.cfl}};
    }
    if (!s.probes.empty()) {
        json probes = json::array();
        for (const ProbeDesc& d : s.probes) probes.push_back(probe_json(d));
        j["probes"] = std::move(probes);
    }
    if (s.standing_wave)
        j["standing_wave"] = json{{"amplitude", s.standing_wave->amplitude},
                                  {"mode", s.standing_wave->mode},
                                  {"at", s.standing_wave->at}};
    return j;
}

namespace {

/// Equal to 1e-12 relative (or 1e-12 m near zero): a value derived in code by another order of
/// the same operations passes, a stale or unset one does not.
bool near(double a, double b) {
    return std::abs(a - b) <= 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
}
bool near(const Vec3d& a, const Vec3d& b) {
    return near(a.x(), b.x()) && near(a.y(), b.y()) && near(a.z(), b.z());
}
bool near(const Aabb& a, const Aabb& b) {
    return near(a.min, b.min) && near(a.max, b.max);
}
std::string box_text(const Aabb& b) {
    return "min " + scene_detail::fmt_vec(b.min) + ", max " + scene_detail::fmt_vec(b.max);
}

/// The values of boundary k that a scene file does not hold (the loader derives them) against
/// those the loader derived from the rest (`back`): a cylinder's box, a height field's vertices,
/// triangles and box, a mesh's box, a circle motion's start.
void check_derived(const std::string& label, std::size_t k, const BoundaryDesc& b, const BoundaryDesc& back) {
    const std::string at = "/boundaries/" + std::to_string(k);
    const std::string shape = to_string(b.shape);
    const auto refuse = [&](const std::string& path, const std::string& found, const std::string& expected) {
        throw SceneError(label, path, found, expected);
    };
    switch (b.shape) {
        case BoundaryShape::Cylinder:
            if (!near(b.box, back.box))
                refuse(at, "a cylinder whose box is " + box_text(b.box),
                       "the box its center, axis, radius and height give, " + box_text(back.box) +
                           " (sph::cylinder_boundary fills it)");
            break;
        case BoundaryShape::Heightfield: {
            bool same = b.vertices.size() == back.vertices.size() && b.triangles == back.triangles;
            for (std::size_t i = 0; same && i < b.vertices.size(); ++i) same = near(b.vertices[i], back.vertices[i]);
            if (!same)
                refuse(at, "a heightfield with " + std::to_string(b.vertices.size()) + " vertices and " +
                               std::to_string(b.triangles.size()) + " triangles that are not its heights' surface",
                       "the " + std::to_string(back.vertices.size()) + " vertices and " +
                           std::to_string(back.triangles.size()) +
                           " triangles its heights give over its box in x and z (sph::heightfield_boundary builds them)");
            if (!near(b.box, back.box))
                refuse(at, "a heightfield whose box is " + box_text(b.box),
                       "its x and z span with the heights' range in y, " + box_text(back.box) +
                           " (sph::heightfield_boundary fills it)");
            break;
        }
        case BoundaryShape::Mesh:
            if (!near(b.box, back.box))
                refuse(at, "a mesh whose box is " + box_text(b.box),
                       "its vertices' bounding box, " + box_text(back.box) + " (sph::mesh_boundary fills it)");
            break;
        default:
            break;
    }
    if (b.motion && back.motion && b.motion->type == MotionType::Circle && !near(b.motion->start, back.motion->start))
        refuse(at + "/motion", "a circle whose start direction is " + scene_detail::fmt_vec(b.motion->start),
               scene_detail::fmt_vec(back.motion->start) + ", the direction of the " + shape +
                   "'s reference point from the circle's centre in its plane (sph::circle_motion with "
                   "sph::reference_point of the boundary gives it)");
}

/// The JSON pointer of the first value where `a` (the scene as built) and `b` (as the loader
/// read it) differ, numbers compared by near(); "" when none. The loader changes what it reads
/// only by normalising (a direction or axis made a unit vector), so a difference is a value set
/// in code that a scene file could not hold.
std::string first_difference(const json& a, const json& b, const std::string& at) {
    if (a.is_number() && b.is_number()) return near(a.get<double>(), b.get<double>()) ? "" : at;
    if (a.type() != b.type()) return at;
    if (a.is_object()) {
        for (auto it = a.begin(); it != a.end(); ++it) {
            const std::string path = at + "/" + it.key();
            if (!b.contains(it.key())) return path;
            if (std::string d = first_difference(it.value(), b.at(it.key()), path); !d.empty()) return d;
        }
        for (auto it = b.begin(); it != b.end(); ++it)
            if (!a.contains(it.key())) return at + "/" + it.key();
        return "";
    }
    if (a.is_array()) {
        if (a.size() != b.size()) return at;
        const auto numbers = [](const json& v) { return std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }); };
        if (numbers(a) && numbers(b)) {  // a vector is named whole
            for (std::size_t i = 0; i < a.size(); ++i)
                if (!near(a[i].get<double>(), b[i].get<double>())) return at;
            return "";
        }
        for (std::size_t i = 0; i < a.size(); ++i)
            if (std::string d = first_difference(a[i], b[i], at + "/" + std::to_string(i)); !d.empty()) return d;
        return "";
    }
    return a == b ? "" : at;
}

}  // namespace

void validate_scene(const Scene& scene) {
    // Non-finite numbers have no JSON form (nlohmann writes null): the loader then names the key
    // and says what it expected, as for a file that held null there.
    const std::string label =
        scene.source.empty() ? "scene \"" + scene.name + "\" (built in code)" : scene.source.string() + " (changed in code)";
    const json written = scene_to_json(scene);
    const Scene back = parse_scene(written.dump(), label);
    for (std::size_t k = 0; k < scene.boundaries.size(); ++k) check_derived(label, k, scene.boundaries[k], back.boundaries[k]);
    for (std::size_t k = 0; k < scene.probes.size(); ++k) {  // a colour front's direction: from `from` to `to`
        const ProbeDesc& d = scene.probes[k];
        if (d.type == ProbeType::Front && d.method == FrontMethod::Colour && !near(d.direction, back.probes[k].direction))
            throw SceneError(label, "/probes/" + std::to_string(k) + "/direction",
                             scene_detail::fmt_vec(d.direction) + " on a colour front",
                             scene_detail::fmt_vec(back.probes[k].direction) +
                                 ", the unit vector from its `from` to its `to`, which the probe reads along");
    }
    // What the loader normalised (a direction, an axis): the scene as read differs from the scene
    // as written where the code set a value a scene file would not give.
    const json reread = scene_to_json(back);
    if (const std::string at = first_difference(written, reread, ""); !at.empty()) {
        const json::json_pointer ptr(at);
        const auto shown = [&](const json& j) { return j.contains(ptr) ? j.at(ptr).dump() : std::string("nothing"); };
        throw SceneError(label, at, shown(written),
                         shown(reread) + ", the value the loader makes of it (a direction or axis is a unit vector: "
                                         "sph::unit)");
    }
}

}  // namespace sph
