#include "engine/run/checkpoint.hpp"

#include <cstring>
#include <fstream>
#include <iterator>
#include <type_traits>

#include "engine/data/components.hpp"
#include "engine/run/io.hpp"
#include "engine/run/simulation.hpp"

#include <limits>

namespace sph {

namespace {



template <class T>
void put(std::string& out, T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

template <class T>
std::string raw_vector(const std::vector<T>& v) {
    return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

/// Reads values from a section, failing with the checkpoint's name when it is too short.
class Cursor {
public:
    Cursor(const std::string& data, std::string what, const std::filesystem::path& file)
        : m_data(data), m_what(std::move(what)), m_file(file) {}
    template <class T>
    T get() {
        T v;
        need(sizeof v);
        std::memcpy(&v, m_data.data() + m_pos, sizeof v);
        m_pos += sizeof v;
        return v;
    }
    template <class T>
    void get_vector(std::vector<T>& v, std::size_t n) {
        need(n * sizeof(T));
        v.resize(n);
        if (n) std::memcpy(v.data(), m_data.data() + m_pos, n * sizeof(T));
        m_pos += n * sizeof(T);
    }
    std::string_view rest() const { return std::string_view(m_data).substr(m_pos); }

private:
    void need(std::size_t n) const {
        if (m_pos + n > m_data.size())
            throw CheckpointError(m_file.string() + ": section '" + m_what + "' is truncated");
    }
    const std::string& m_data;
    std::string m_what;
    const std::filesystem::path& m_file;
    std::size_t m_pos = 0;
};

// Slab lists (capacity > 0) are stored as the slab; compact lists (capacity 0) as their
// entries one after another (NeighbourLists::concatenated).
std::string lists_section(const NeighbourLists& l) {
    std::string s;
    const std::vector<Index> compact = l.compact() ? l.concatenated() : std::vector<Index>{};
    const std::vector<Index>& entries = l.compact() ? compact : l.indices;
    const std::vector<Index> counts = l.counts();
    put(s, std::uint64_t(l.capacity));
    put(s, std::uint64_t(counts.size()));
    put(s, std::uint64_t(entries.size()));
    s += raw_vector(counts);
    s += raw_vector(entries);
    return s;
}

/// @param rows the fluid rows (a list has at most that many: rows emitted since it was built have none)
/// @param targets the rows its entries index (fluid or boundary particles): every entry read
/// must lie below, so that a damaged file with a valid checksum cannot index out of bounds.
void restore_lists(NeighbourLists& l, const std::string& data, const std::string& what,
                   const std::filesystem::path& file, std::size_t rows, std::size_t targets) {
    Cursor c(data, what, file);
    l.capacity = Index(c.get<std::uint64_t>());
    const auto nc = std::size_t(c.get<std::uint64_t>());
    const auto ni = std::size_t(c.get<std::uint64_t>());
    const auto bad = [&](const std::string& why) {
        return CheckpointError(file.string() + ": section '" + what + "' " + why);
    };
    if (nc > rows)
        throw bad("holds lists of " + std::to_string(nc) + " rows, the fluid has " + std::to_string(rows));
    if (l.capacity > 0 && ni != nc * std::size_t(l.capacity))
        throw bad("holds " + std::to_string(ni) + " slab entries, expected rows x capacity = " +
                  std::to_string(nc * std::size_t(l.capacity)));
    c.get_vector(l.count, nc);
    c.get_vector(l.indices, ni);
    if (l.capacity > 0) {
        for (std::size_t i = 0; i < nc; ++i) {
            if (l.count[i] > l.capacity)
                throw bad("row " + std::to_string(i) + " counts " + std::to_string(l.count[i]) +
                          " neighbours, above the slab's capacity " + std::to_string(l.capacity));
            for (std::size_t k = 0; k < l.count[i]; ++k)
                if (l.indices[i * l.capacity + k] >= targets)
                    throw bad("row " + std::to_string(i) + " names particle " +
                              std::to_string(l.indices[i * l.capacity + k]) + " of " + std::to_string(targets));
        }
        return;
    }
    std::uint64_t sum = 0;
    for (Index k : l.count) sum += k;
    if (sum != ni)
        throw CheckpointError(file.string() + ": section '" + what + "' holds " + std::to_string(ni) +
                              " neighbour entries, but its counts sum to " + std::to_string(sum));
    for (Index j : l.indices)
        if (j >= targets) throw bad("names particle " + std::to_string(j) + " of " + std::to_string(targets));
    std::vector<Index> entries, counts;
    entries.swap(l.indices);
    counts.swap(l.count);
    l.assign_compact(counts, entries);
}

std::string column_section(const ComponentStore& store, const std::string& name) {
    std::string s;
    put(s, std::uint32_t(store.element_size(name)));
    const auto raw = store.raw(name);
    s.append(reinterpret_cast<const char*>(raw.data()), raw.size());
    return s;
}

void restore_store(ComponentStore& store, const std::string& set, const Checkpoint& ck) {
    const std::string prefix = set + "/";
    std::vector<std::string> saved;
    for (const auto& [name, data] : ck.sections)
        if (name.rfind(prefix, 0) == 0) saved.push_back(name.substr(prefix.size()));
    // Checkpoints written before the boundary's normals became a column of the methods that read
    // them carry `boundary/normal` for every method; the scene gives the normals again.
    if (set == "boundary" && !store.has(comp::normal.name))
        std::erase(saved, std::string(comp::normal.name));
    if (saved != store.names()) {
        std::string a, b;
        for (const auto& n : saved) a += (a.empty() ? "" : ", ") + n;
        for (const auto& n : store.names()) b += (b.empty() ? "" : ", ") + n;
        throw CheckpointError(ck.file.string() + ": the checkpoint's " + set + " columns (" + a +
                              ") are not the ones this scene's method uses (" + b + ")");
    }
    std::size_t count = SIZE_MAX;
    for (const auto& name : saved) {
        const std::string& data = ck.sections.at(prefix + name);
        Cursor c(data, prefix + name, ck.file);
        const std::uint32_t size = c.get<std::uint32_t>();
        if (size != store.element_size(name) || c.rest().size() % size != 0)
            throw CheckpointError(ck.file.string() + ": column " + prefix + name + " has " + std::to_string(size) +
                                  "-byte values, this build stores " + std::to_string(store.element_size(name)));
        const std::size_t n = c.rest().size() / size;
        if (count != SIZE_MAX && n != count)
            throw CheckpointError(ck.file.string() + ": the " + set + " columns have different lengths");
        count = n;
    }
    if (count == SIZE_MAX) count = 0;
    store.resize(count);
    for (const auto& name : saved) {
        const std::string& data = ck.sections.at(prefix + name);
        auto raw = store.raw(name);
        std::memcpy(raw.data(), data.data() + 4, raw.size());
    }
}

std::uint64_t bits_of(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, 8);
    return b;
}
double real_of(std::uint64_t b) {
    double v;
    std::memcpy(&v, &b, 8);
    return v;
}

/// A saved state's clock (the rollback ring's): its end time too, which the state restores.
nlohmann::json clock_section(const Clock& c) {
    return {{"t_ticks", c.t_ticks}, {"step", c.step}, {"rollbacks", c.rollbacks},
            {"rows_since_sort", c.rows_since_sort}, {"t_stop", bits_of(c.t_stop)}};
}

/// One column of a saved state: u32 element size, then the raw values (as column_section).
std::string snapshot_column(ColumnBase& col) {
    std::string s;
    put(s, std::uint32_t(col.element_size()));
    const auto raw = col.raw();
    s.append(reinterpret_cast<const char*>(raw.data()), raw.size());
    return s;
}

/// The rollback ring's states, oldest first: "ring/<k>/clock", "ring/<k>/fluid/<column>",
/// "ring/<k>/boundary/<column>", "ring/<k>/resource/<name>".
void ring_sections(const StateRing& ring, std::map<std::string, std::string>& sections) {
    const auto held = ring.held();
    for (std::size_t k = 0; k < held.size(); ++k) {
        const std::string p = "ring/" + std::to_string(k) + "/";
        const StateRing::State& st = *held[k];
        sections[p + "clock"] = clock_section(st.clock).dump();
        for (const auto& [name, col] : st.fluid.columns) sections[p + "fluid/" + name] = snapshot_column(*col);
        for (const auto& [name, col] : st.boundary.columns) sections[p + "boundary/" + name] = snapshot_column(*col);
        for (const auto& [name, r] : st.resources) sections[p + "resource/" + name] = r->bytes();
    }
}

/// Refills the ring from the checkpoint's "ring/<k>/..." sections (a checkpoint written before
/// 2026-12-07 has none: returns false). Each state is first saved from the restored world, which
/// gives its columns and resources this recipe's types, then overwritten.
bool restore_ring(StateRing& ring, const World& w, const Checkpoint& ck) {
    const auto bad = [&](const std::string& section, const std::string& why) {
        return CheckpointError(ck.file.string() + ": section '" + section + "' " + why);
    };
    std::size_t states = 0;
    while (ck.sections.count("ring/" + std::to_string(states) + "/clock")) ++states;
    if (states == 0) return false;
    if (states > ring.depth())
        throw bad("ring/" + std::to_string(states - 1) + "/clock",
                  "is one of " + std::to_string(states) + " saved states; this recipe keeps " + std::to_string(ring.depth()));
    for (std::size_t k = 0; k < states; ++k) {
        const std::string p = "ring/" + std::to_string(k) + "/";
        StateRing::State& st = ring.push(w);
        try {
            const nlohmann::json c = nlohmann::json::parse(ck.sections.at(p + "clock"));
            st.clock.t_ticks = c.at("t_ticks").get<Tick>();
            st.clock.t = to_seconds(st.clock.t_ticks);
            st.clock.step = c.at("step").get<std::int64_t>();
            st.clock.rollbacks = c.at("rollbacks").get<std::uint64_t>();
            st.clock.rows_since_sort = c.at("rows_since_sort").get<std::uint64_t>();
            st.clock.t_stop = real_of(c.at("t_stop").get<std::uint64_t>());
        } catch (const nlohmann::json::exception& e) {
            throw bad(p + "clock", std::string("is not a saved clock (") + e.what() + ")");
        }
        for (const auto& [set, snap] : {std::pair<const char*, ComponentStore::Snapshot*>{"fluid", &st.fluid},
                                        std::pair<const char*, ComponentStore::Snapshot*>{"boundary", &st.boundary}}) {
            std::size_t count = SIZE_MAX;
            for (auto& [name, col] : snap->columns) {
                const std::string section = p + set + "/" + name;
                const auto it = ck.sections.find(section);
                if (it == ck.sections.end()) throw bad(section, "is missing");
                Cursor cur(it->second, section, ck.file);
                const std::uint32_t size = cur.get<std::uint32_t>();
                if (size != col->element_size() || cur.rest().size() % size != 0)
                    throw bad(section, "has " + std::to_string(size) + "-byte values, this build stores " +
                                           std::to_string(col->element_size()));
                const std::size_t n = cur.rest().size() / size;
                if (count != SIZE_MAX && n != count) throw bad(section, "has another length than the state's other columns");
                count = n;
                col->resize(n);
                std::memcpy(col->raw().data(), it->second.data() + 4, n * size);
            }
            snap->size = count == SIZE_MAX ? 0 : count;
        }
        for (auto& [name, r] : st.resources) {
            const auto it = ck.sections.find(p + "resource/" + name);
            if (it == ck.sections.end()) throw bad(p + "resource/" + name, "is missing");
            try {
                r->load(it->second);
            } catch (const std::runtime_error& e) {
                throw bad(p + "resource/" + name, e.what());
            }
        }
    }
    return true;
}

/// The clock, the step size, the statistics, the rollback state and the counters, by name.
/// Doubles are written as their exact bit patterns (JSON numbers would round-trip too, but
/// infinities would not).
nlohmann::json step_section(const World& w) {
    nlohmann::json j;
    j["clock"] = {{"t_ticks", w.clock.t_ticks}, {"step", w.clock.step}, {"rollbacks", w.clock.rollbacks},
                  {"rows_since_sort", w.clock.rows_since_sort}};
    j["step_size"] = {{"dt_ticks", w.step_size.dt_ticks}, {"dt", bits_of(w.step_size.dt)},
                      {"dt_stable", bits_of(w.step_size.dt_stable)}};
    j["stats"] = {{"rho_err_avg", bits_of(w.stats.rho_err_avg)}, {"rho_err_max", bits_of(w.stats.rho_err_max)},
                  {"v_max", bits_of(w.stats.v_max)}, {"a_max", bits_of(w.stats.a_max)},
                  {"a_max_particle", w.stats.a_max_particle}};
    j["rollback"] = {{"resume_dt", bits_of(w.rollback.resume_dt)}};
    j["counters"] = nlohmann::json::object();
    for (const auto& [name, v] : w.counters) j["counters"][name] = v;
    return j;
}

void restore_step(World& w, const std::string& text, const std::filesystem::path& file) {
    try {
        const nlohmann::json j = nlohmann::json::parse(text);
        const auto& c = j.at("clock");
        w.clock.t_ticks = c.at("t_ticks").get<Tick>();
        w.clock.t = to_seconds(w.clock.t_ticks);
        w.clock.step = c.at("step").get<std::int64_t>();
        w.clock.rollbacks = c.at("rollbacks").get<std::uint64_t>();
        w.clock.rows_since_sort = c.at("rows_since_sort").get<std::uint64_t>();
        w.clock.t_stop = std::numeric_limits<double>::infinity();
        const auto& d = j.at("step_size");
        w.step_size.dt_ticks = d.at("dt_ticks").get<Tick>();
        w.step_size.dt = real_of(d.at("dt").get<std::uint64_t>());
        w.step_size.dt_stable = real_of(d.at("dt_stable").get<std::uint64_t>());
        const auto& st = j.at("stats");
        w.stats.rho_err_avg = real_of(st.at("rho_err_avg").get<std::uint64_t>());
        w.stats.rho_err_max = real_of(st.at("rho_err_max").get<std::uint64_t>());
        w.stats.v_max = real_of(st.at("v_max").get<std::uint64_t>());
        w.stats.a_max = real_of(st.at("a_max").get<std::uint64_t>());
        w.stats.a_max_particle = st.at("a_max_particle").get<Index>();
        w.rollback.resume_dt = real_of(j.at("rollback").at("resume_dt").get<std::uint64_t>());
        for (const auto& [name, v] : j.at("counters").items()) {
            if (!w.counters.count(name))
                throw CheckpointError(file.string() + ": section 'step' has counter '" + name +
                                      "', which no system of this scene's method declares");
            w.counters[name] = v.get<std::uint64_t>();
        }
    } catch (const nlohmann::json::exception& e) {
        throw CheckpointError(file.string() + ": section 'step' is not this version's step state (" + e.what() + ")");
    }
}

}  // namespace

void write_checkpoint(const std::filesystem::path& file, const Simulation& sim, const nlohmann::json& meta) {
    const World& w = sim.world();
    std::map<std::string, std::string> sections;
    sections["meta"] = meta.dump();
    sections["step"] = step_section(w).dump();
    for (const auto& [name, r] : w.resources.items())
        if (r->lifetime() == Lifetime::Kept) sections["resource/" + name] = r->bytes();
    for (const auto& name : w.fluid.store.names()) sections["fluid/" + name] = column_section(w.fluid.store, name);
    for (const auto& name : w.boundary.store.names())
        sections["boundary/" + name] = column_section(w.boundary.store, name);
    sections["fluid_neighbours"] = lists_section(w.fluid_neighbours);
    sections["boundary_neighbours"] = lists_section(w.boundary_neighbours);
    sections["active_set"] = raw_vector(w.active_set);
    sections["halo_set"] = raw_vector(w.halo_set);
    std::string bodies;
    for (const MovingBody& b : w.moving_bodies) {
        put(bodies, std::uint64_t(b.begin));
        put(bodies, std::uint64_t(b.end));
        put(bodies, std::uint64_t(b.boundary));
        for (int a = 0; a < 3; ++a) put(bodies, b.bounds.min[a]);
        for (int a = 0; a < 3; ++a) put(bodies, b.bounds.max[a]);
        put(bodies, b.speed);
    }
    sections["moving_bodies"] = bodies;
    if (const StateRing* ring = sim.ring()) ring_sections(*ring, sections);

    std::string payload;
    for (const auto& [name, data] : sections) {
        put(payload, std::uint32_t(name.size()));
        payload += name;
        put(payload, std::uint64_t(data.size()));
        payload += data;
    }
    std::string out(kCheckpointMagic, sizeof kCheckpointMagic);
    put(out, kCheckpointVersion);
    put(out, std::uint32_t(sizeof(Real)));
    put(out, std::uint64_t(payload.size()));
    put(out, fnv1a64(payload));
    AtomicFile f(file);
    f.write(out);
    f.write(payload);
    f.commit();
}

void restore_checkpoint(Simulation& sim, const Checkpoint& ck) {
    World& w = sim.world();
    // The boundary is sampled from the scene again; a different sampling (another engine
    // version) would silently change the physics, so the static part must match exactly.
    if (ck.sections.count("boundary/position")) {
        const std::string& b = ck.sections.at("boundary/position");
        const auto now = w.boundary.store.raw("position");
        const std::size_t n = std::min(now.size(), std::size_t(w.static_boundary_end) * sizeof(Vec3));
        if (b.size() != 4 + now.size() || std::memcmp(b.data() + 4, now.data(), n) != 0)
            throw CheckpointError(ck.file.string() +
                                  ": the boundary particles differ from this scene's sampling (another scene "
                                  "or another engine version)");
    }
    restore_store(w.fluid.store, "fluid", ck);
    restore_store(w.boundary.store, "boundary", ck);
    const std::size_t n_fluid = w.fluid.size(), n_boundary = w.boundary.size();
    restore_lists(w.fluid_neighbours, ck.sections.at("fluid_neighbours"), "fluid_neighbours", ck.file, n_fluid, n_fluid);
    restore_lists(w.boundary_neighbours, ck.sections.at("boundary_neighbours"), "boundary_neighbours", ck.file, n_fluid,
                  n_boundary);
    {
        Cursor c(ck.sections.at("active_set"), "active_set", ck.file);
        c.get_vector(w.active_set, ck.sections.at("active_set").size() / sizeof(Index));
        Cursor h(ck.sections.at("halo_set"), "halo_set", ck.file);
        h.get_vector(w.halo_set, ck.sections.at("halo_set").size() / sizeof(Index));
        for (const auto* set : {&w.active_set, &w.halo_set})
            for (Index i : *set)
                if (i >= n_fluid)
                    throw CheckpointError(ck.file.string() + ": section '" +
                                          (set == &w.active_set ? "active_set" : "halo_set") + "' names particle " +
                                          std::to_string(i) + " of " + std::to_string(n_fluid));
    }
    {
        const std::string& data = ck.sections.at("moving_bodies");
        Cursor c(data, "moving_bodies", ck.file);
        const std::size_t record = 3 * 8 + 7 * 8;
        if (data.size() != record * w.moving_bodies.size())
            throw CheckpointError(ck.file.string() + ": the checkpoint has " + std::to_string(data.size() / record) +
                                  " moving bodies, the scene " + std::to_string(w.moving_bodies.size()));
        for (MovingBody& b : w.moving_bodies) {
            b.begin = std::size_t(c.get<std::uint64_t>());
            b.end = std::size_t(c.get<std::uint64_t>());
            b.boundary = std::size_t(c.get<std::uint64_t>());
            for (int a = 0; a < 3; ++a) b.bounds.min[a] = c.get<double>();
            for (int a = 0; a < 3; ++a) b.bounds.max[a] = c.get<double>();
            b.speed = c.get<double>();
            if (!(b.begin <= b.end && b.end <= n_boundary))
                throw CheckpointError(ck.file.string() + ": section 'moving_bodies' has a body of boundary rows [" +
                                      std::to_string(b.begin) + ", " + std::to_string(b.end) + ") of " +
                                      std::to_string(n_boundary));
        }
    }
    restore_step(w, ck.sections.at("step"), ck.file);
    // Every Kept resource of this scene's method, and no other.
    for (const auto& [name, r] : w.resources.items()) {
        if (r->lifetime() != Lifetime::Kept) continue;
        const auto it = ck.sections.find("resource/" + name);
        if (it == ck.sections.end())
            throw CheckpointError(ck.file.string() + ": section 'resource/" + name + "' is missing");
        try {
            r->load(it->second);
        } catch (const std::runtime_error& e) {
            throw CheckpointError(ck.file.string() + ": section 'resource/" + name + "' " + e.what());
        }
    }
    for (const auto& [key, data] : ck.sections)
        if (key.rfind("resource/", 0) == 0 && !w.resources.has(key.substr(9)))
            throw CheckpointError(ck.file.string() + ": section '" + key +
                                  "' is a resource this scene's method does not have");
    sim.forget_history();  // the rollback ring held states of the world before the restore
    if (StateRing* ring = sim.ring(); ring && restore_ring(*ring, w, ck)) sim.history_restored();
}

}  // namespace sph
