/// @file probe_desc.cpp
/// @brief Parsing and validation of the scene key `probes` (engine/probe_desc.hpp). Kept apart from
/// the measurements (engine/probes.cpp) so the scene loader links without the simulation (the
/// loader fuzzer, tools/fuzz.sh, builds only the loader).
#include "engine/data/probe_desc.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_set>

#include "engine/core/errors.hpp"

namespace sph {

using json = nlohmann::json;

const char* to_string(ProbeType t) {
    switch (t) {
        case ProbeType::Pressure:
            return "pressure";
        case ProbeType::Height:
            return "height";
        case ProbeType::Front:
            return "front";
        case ProbeType::Fluid:
            return "fluid";
    }
    return "unknown";
}

const char* to_string(PressureSource s) {
    switch (s) {
        case PressureSource::Fluid:
            return "fluid";
        case PressureSource::Boundary:
            return "boundary";
        case PressureSource::Sensor:
            return "sensor";
    }
    return "unknown";
}
const char* to_string(FrontMethod m) {
    switch (m) {
        case FrontMethod::Neighbours:
            return "neighbours";
        case FrontMethod::Colour:
            return "colour";
    }
    return "unknown";
}
const char* to_string(HeightMethod m) {
    switch (m) {
        case HeightMethod::Column:
            return "column";
        case HeightMethod::Highest:
            return "highest";
    }
    return "unknown";
}

// ---------------------------------------------------------------------------------------------
// Parsing
// ---------------------------------------------------------------------------------------------
namespace {

class ProbeReader {
public:
    ProbeReader(const std::string& file) : m_file(file) {}

    /// The `found` of a key that is not there (a null there is shown as null).
    static json missing() { return json(json::value_t::discarded); }
    [[noreturn]] void fail(const std::string& path, const json& found, const std::string& expected) const {
        std::string f = found.is_discarded() ? "nothing" : found.dump();
        if (f.size() > 80) f = f.substr(0, 77) + "...";
        throw SceneError(m_file, path, f, expected);
    }
    void keys(const json& obj, const std::string& path, std::initializer_list<const char*> allowed,
              const std::string& context) const {
        for (const auto& item : obj.items()) {
            const std::string& k = item.key();  // not a structured binding: clang 14 cannot capture one
            if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return k == a; }) != allowed.end())
                continue;
            std::string list;
            for (const char* a : allowed) list += (list.empty() ? "" : ", ") + json(a).dump();
            throw SceneError(m_file, path + "/" + k, "an unknown key " + json(k).dump(),
                             "one of " + list + context);
        }
    }
    double number(const json& obj, const std::string& path, const char* key, double lo, bool lo_incl,
                  const char* what, std::optional<double> fallback) const {
        const auto it = obj.find(key);
        if (it == obj.end()) {
            if (fallback) return *fallback;
            fail(path + "/" + key, missing(), what);
        }
        if (!it->is_number() || !std::isfinite(it->get<double>())) fail(path + "/" + key, *it, what);
        const double x = it->get<double>();
        if (lo_incl ? x < lo : x <= lo) fail(path + "/" + key, *it, what);
        return x;
    }
    Vec3d vec3(const json& obj, const std::string& path, const char* key, std::optional<Vec3d> fallback) const {
        const char* what = "an array of 3 numbers (metres)";
        const auto it = obj.find(key);
        if (it == obj.end()) {
            if (fallback) return *fallback;
            fail(path + "/" + key, missing(), what);
        }
        if (!it->is_array() || it->size() != 3) fail(path + "/" + key, *it, what);
        Vec3d v;
        for (int a = 0; a < 3; ++a) {
            const json& e = (*it)[std::size_t(a)];
            if (!e.is_number() || !std::isfinite(e.get<double>())) fail(path + "/" + key, *it, what);
            v[a] = e.get<double>();
        }
        return v;
    }
    std::string word(const json& obj, const std::string& path, const char* key,
                     std::initializer_list<const char*> allowed, const char* fallback) const {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + json(a).dump();
        const auto it = obj.find(key);
        if (it == obj.end()) {
            if (fallback) return fallback;
            fail(path + "/" + key, missing(), "one of " + list);
        }
        if (!it->is_string()) fail(path + "/" + key, *it, "one of " + list);
        const std::string s = it->get<std::string>();
        if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return s == a; }) == allowed.end())
            fail(path + "/" + key, *it, "one of " + list);
        return s;
    }

    ProbeExperiment experiment(const json& e, const std::string& path) const {
        if (!e.is_object()) fail(path, e, "an object with file, t_scale, value_scale");
        keys(e, path, {"file", "t_scale", "value_scale", "value_offset", "max_shift", "t_range"}, "");
        ProbeExperiment x;
        const auto f = e.find("file");
        if (f == e.end() || !f->is_string() || f->get<std::string>().empty())
            fail(path + "/file", f == e.end() ? missing() : *f, "a CSV file name, relative to the scene file");
        x.file = f->get<std::string>();
        x.t_scale = number(e, path, "t_scale", 0, false, "a number > 0 (1/s: T = t * t_scale)", 1.0);
        x.value_scale = number(e, path, "value_scale", 0, false, "a number > 0 (Z = (value - value_offset) * value_scale)", 1.0);
        x.value_offset = number(e, path, "value_offset", -1e300, false, "a number", 0.0);
        x.max_shift = number(e, path, "max_shift", 0, true, "a number >= 0 (largest time shift |dT|)", 0.0);
        if (const auto r = e.find("t_range"); r != e.end()) {
            if (!r->is_array() || r->size() != 2 || !(*r)[0].is_number() || !(*r)[1].is_number() ||
                !((*r)[0].get<double>() < (*r)[1].get<double>()))
                fail(path + "/t_range", *r, "[T_min, T_max] with T_min < T_max");
            x.t_min = (*r)[0].get<double>();
            x.t_max = (*r)[1].get<double>();
        }
        return x;
    }

    ProbeDesc probe(const json& p, const std::string& path, std::size_t index) const {
        if (!p.is_object()) fail(path, p, "an object with a type (a probe)");
        const std::string type = word(p, path, "type", {to_string(ProbeType::Pressure), to_string(ProbeType::Height),
                                                        to_string(ProbeType::Front), to_string(ProbeType::Fluid)},
                                      nullptr);
        ProbeDesc d;
        const std::string ctx = " for a " + json(type).dump() + " probe";
        if (type == to_string(ProbeType::Pressure)) {
            d.type = ProbeType::Pressure;
            keys(p, path, {"type", "name", "rate", "experiment", "point", "source", "radius", "diameter", "normal"}, ctx);
            d.point = vec3(p, path, "point", std::nullopt);
            constexpr PressureSource kSources[] = {PressureSource::Fluid, PressureSource::Boundary, PressureSource::Sensor};
            const std::string source = word(p, path, "source", {to_string(kSources[0]), to_string(kSources[1]),
                                                                to_string(kSources[2])}, to_string(kSources[0]));
            d.source = *std::find_if(std::begin(kSources), std::end(kSources), [&](PressureSource k) { return source == to_string(k); });
            if (d.source != PressureSource::Boundary && p.contains("radius"))
                fail(path + "/radius", p["radius"], "no radius unless source is \"boundary\" (a sensor has a diameter)");
            d.radius = number(p, path, "radius", 0, false, "a number > 0 (metres)", 0.0);
            if (d.source != PressureSource::Sensor) {
                for (const char* k : {"diameter", "normal"})
                    if (p.contains(k)) fail(path + "/" + k, p[k], std::string("no ") + k + " unless source is \"sensor\"");
            } else {
                if (!p.contains("diameter")) fail(path + "/diameter", missing(), "the sensor face's diameter (a number > 0, metres)");
                d.diameter = number(p, path, "diameter", 0, false, "a number > 0 (metres)", 0.0);
                d.normal = vec3(p, path, "normal", std::nullopt);
                if (!(d.normal.norm() > 0)) fail(path + "/normal", p["normal"], "a non-zero vector (the wall's normal at the sensor)");
                d.normal = unit(d.normal);
            }
        } else if (type == to_string(ProbeType::Height)) {
            d.type = ProbeType::Height;
            keys(p, path, {"type", "name", "rate", "experiment", "from", "to", "method"}, ctx);
            const char* column = to_string(HeightMethod::Column);
            d.height_method = word(p, path, "method", {column, to_string(HeightMethod::Highest)}, column) == column
                                  ? HeightMethod::Column
                                  : HeightMethod::Highest;
            d.from = vec3(p, path, "from", std::nullopt);
            d.to = vec3(p, path, "to", std::nullopt);
            if ((d.to - d.from).norm() <= 0) fail(path + "/to", p["to"], "a point different from \"from\"");
        } else if (type == to_string(ProbeType::Front)) {
            d.type = ProbeType::Front;
            const char* neighbours = to_string(FrontMethod::Neighbours);
            d.method = word(p, path, "method", {neighbours, to_string(FrontMethod::Colour)}, neighbours) == neighbours
                           ? FrontMethod::Neighbours
                           : FrontMethod::Colour;
            if (d.method == FrontMethod::Neighbours) {
                keys(p, path, {"type", "name", "rate", "experiment", "method", "direction", "min_neighbours"},
                     ctx + " by neighbours");
                d.direction = vec3(p, path, "direction", Vec3d(1, 0, 0));
                if (!(d.direction.norm() > 0)) fail(path + "/direction", p["direction"], "a direction, not all zero");
                d.direction = unit(d.direction);
                const double k = number(p, path, "min_neighbours", 0, true, "an integer >= 0", 4.0);
                if (k != std::floor(k) || k > 1000) fail(path + "/min_neighbours", p["min_neighbours"], "an integer >= 0");
                d.min_neighbours = int(k);
            } else {
                keys(p, path, {"type", "name", "rate", "experiment", "method", "from", "to"}, ctx + " by colour");
                d.from = vec3(p, path, "from", std::nullopt);
                d.to = vec3(p, path, "to", std::nullopt);
                if ((d.to - d.from).norm() <= 0) fail(path + "/to", p["to"], "a point different from \"from\"");
                d.direction = (d.to - d.from).normalized();
            }
        } else {
            d.type = ProbeType::Fluid;
            keys(p, path, {"type", "name", "rate", "experiment"}, ctx);
        }
        d.rate = number(p, path, "rate", 0, false, "a number > 0 (samples per simulated second)", 100.0);
        d.name = type + "_" + std::to_string(index);
        if (const auto n = p.find("name"); n != p.end()) {
            const char* what =
                "a non-empty name of at most 251 letters, digits, '_', '-' or '.' (it names probes/<name>.csv, and a "
                "file name holds at most 255 bytes)";
            if (!n->is_string() || n->get<std::string>().empty() || n->get<std::string>().size() > 251)
                fail(path + "/name", *n, what);
            for (const char c : n->get<std::string>())
                if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
                    fail(path + "/name", *n, what);
            d.name = n->get<std::string>();
        }
        if (const auto e = p.find("experiment"); e != p.end()) d.experiment = experiment(*e, path + "/experiment");
        return d;
    }

private:
    const std::string& m_file;
};

}  // namespace

std::vector<ProbeDesc> parse_probes(const json& value, const std::string& file, const std::string& path) {
    ProbeReader r(file);
    if (!value.is_array()) r.fail(path, value, "an array of probes");
    std::vector<ProbeDesc> out;
    std::unordered_set<std::string> names;  // one lookup a probe: linear in the probe count
    for (std::size_t i = 0; i < value.size(); ++i) {
        out.push_back(r.probe(value[i], path + "/" + std::to_string(i), i));
        if (!names.insert(out.back().name).second)
            r.fail(path + "/" + std::to_string(i) + "/name", json(out.back().name),
                   "a name no other probe has (it names probes/<name>.csv)");
    }
    return out;
}

}  // namespace sph
