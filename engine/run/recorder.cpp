#include "engine/run/recorder.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <iomanip>
#include <sstream>

#include "engine/core/simd.hpp"
#include "engine/data/components.hpp"
#include "engine/core/errors.hpp"
#include "engine/graph/system.hpp"
#include "engine/run/io.hpp"
#include "engine/run/probes.hpp"
#include "engine/run/surface.hpp"

namespace sph {

double front_x(const World& w) {
    // The largest x of a fluid particle with at least 4 fluid neighbours within h (so a lone
    // droplet thrown ahead is not the front), in metres; 0 without such a particle. Counted on a
    // grid built here, not read from the neighbour lists: `individual` and `binned` keep lists
    // only for the rows they evaluated last, so a sleeping front row has none (the summary's
    // front read 0 m in a binned run). A whole-fluid pass at frame times and at the end.
    UniformGrid grid(w.domain, w.physics.h);
    grid.build(w.fluid.store.get(comp::position));
    const double front = front_by_neighbours(w, grid, Vec3d(1, 0, 0), 4);
    return std::isfinite(front) ? front : 0.0;
}

namespace {
/// Refuses the surface formats before the run starts when this build has no OpenVDB.
void check_surface_formats(const World& w) {
    if (!w.scene.output.writes_surface() || surface_available()) return;
    const FrameFormat f = w.scene.output.writes(FrameFormat::Vdb) ? FrameFormat::Vdb : FrameFormat::Mesh;
    throw InputError(std::string("output format \"") + to_string(f) +
                     "\" needs OpenVDB: this build has SPH_WITH_OPENVDB=OFF (rebuild with it ON, or choose "
                     "vtu, bgeo or ply)");
}
/// The scene as this run runs it (every override applied: `sph-run DIR/scene_as_run.json` runs it again),
/// with the experiment files of its probes made absolute, since the file no longer sits beside them.
void write_scene(const std::filesystem::path& dir, const Scene& scene) {
    nlohmann::json j = scene_to_json(scene);
    if (!scene.source.empty() && j.contains("probes"))
        for (auto& probe : j["probes"])
            if (probe.contains("experiment")) {
                const std::filesystem::path f = probe["experiment"]["file"].get<std::string>();
                if (f.is_relative()) probe["experiment"]["file"] = (std::filesystem::absolute(scene.source).parent_path() / f).lexically_normal().string();
            }
    write_file_atomic(dir / "scene_as_run.json", j.dump(2) + "\n");
}
constexpr std::size_t kMaxPendingStats = std::size_t(4) << 20;  // bytes of rows held in memory
/// Room kept for salvage(): the most pending stats rows, plus summary.json and probes.
constexpr std::size_t kReserveBytes = kMaxPendingStats + (std::size_t(1) << 20);
constexpr const char* kReserveName = ".sph-reserve";
}

void Recorder::reserve_space() {
    const auto file = m_dir / kReserveName;
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
        throw OutputError(file.string() + ": cannot create the reserve (" + std::strerror(errno) + ")");
    int rc = ::posix_fallocate(fd, 0, off_t(kReserveBytes));
    if (rc == EOPNOTSUPP || rc == EINVAL) {  // a file system without fallocate: write the bytes
        const std::string zeros(std::size_t(1) << 16, '\0');
        rc = 0;
        for (std::size_t done = 0; done < kReserveBytes && rc == 0; done += zeros.size())
            if (::pwrite(fd, zeros.data(), zeros.size(), off_t(done)) != ssize_t(zeros.size())) rc = errno;
    }
    ::close(fd);
    if (rc != 0) {
        std::error_code ec;
        std::filesystem::remove(file, ec);
        throw OutputError(m_dir.string() + ": no room for the " + std::to_string(kReserveBytes >> 20) +
                          " MiB the run keeps to save its records if the disk fills (" + std::strerror(rc) + ")");
    }
}

Recorder::~Recorder() { release_reserve(); }

void Recorder::release_reserve() {
    std::error_code ec;
    std::filesystem::remove(m_dir / kReserveName, ec);
}

std::vector<std::string> Recorder::salvage(const Simulation& sim, const std::string& reason, double wall_seconds,
                                           int threads) {
    release_reserve();
    std::vector<std::string> report;
    m_output_failed = reason;
    // stats.csv: its committed bytes are intact; the pending rows go after them in place (an
    // AtomicFile would need room for a second copy of the whole file).
    const auto csv = m_dir / "stats.csv";
    const std::size_t rows = std::size_t(std::count(m_pending.begin(), m_pending.end(), '\n')) -
                             (m_stats_bytes == 0 && !m_pending.empty() ? 1 : 0);  // not the header
    const int fd = ::open(csv.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    bool ok = fd >= 0 && ::ftruncate(fd, off_t(m_stats_bytes)) == 0;
    for (std::size_t done = 0; ok && done < m_pending.size();) {
        const ssize_t n = ::pwrite(fd, m_pending.data() + done, m_pending.size() - done, off_t(m_stats_bytes + done));
        ok = n > 0;
        if (ok) done += std::size_t(n);
    }
    const std::string why = std::strerror(errno);
    if (ok) {
        m_stats_bytes += m_pending.size();
        m_pending.clear();
        report.push_back("stats.csv: complete to t = " + std::to_string(sim.time()) + " s (" + std::to_string(rows) +
                         " rows saved from memory)");
    } else {
        if (fd >= 0) [[maybe_unused]] const int back = ::ftruncate(fd, off_t(m_stats_bytes));  // whole rows only
        m_pending.clear();  // lost: finish() must not try them again
        report.push_back("stats.csv: " + std::to_string(rows) + " rows could not be saved (" + why + ")");
    }
    if (fd >= 0) ::close(fd);
    try {
        finish(sim, wall_seconds, threads);
        report.emplace_back("summary.json: written, marked \"output_failed\"");
    } catch (const std::exception& e) {
        report.push_back(std::string("summary.json: not written (") + e.what() + ")");
    }
    try {
        m_probes.write(m_dir);
        if (!sim.world().scene.probes.empty()) report.emplace_back("probes/: written");
    } catch (const std::exception& e) {
        report.push_back(std::string("probes/: not written (") + e.what() + ")");
    }
    return report;
}

// The stats.csv schema: these columns in this order in every run (a counter no system of the
// recipe declares reads 0), then any other declared counter by name, then the timings.
constexpr std::array<const char*, 8> kCounterColumns{"collisions",        "active",
                                                     "neighbour_searches", "force_evaluations",
                                                     "boundary_contributions", "propagation_updates",
                                                     "iterations",        "boundary_active"};

std::vector<std::string> extra_counters(const World& w) {
    std::vector<std::string> out;
    for (const auto& [name, v] : w.counters) {
        const bool standard = name == "updated" || name == "neighbour_pairs" ||
                              std::find(kCounterColumns.begin(), kCounterColumns.end(), name) != kCounterColumns.end();
        if (!standard) out.push_back(name);
    }
    return out;
}

std::string Recorder::header(const Simulation& sim) {
    std::ostringstream h;
    h << "step,t,dt,updated,neighbours_per_particle,rho_err_avg,rho_err_max,v_max,a_max,collisions,"
         "active,active_fraction,neighbour_searches,force_evaluations,boundary_contributions,"
         "propagation_updates,iterations,boundary_active,rolled_back,v_mean,whole_fluid";
    for (const auto& name : extra_counters(sim.world())) h << ',' << name;
    h << ",wall_s";
    for (const auto& s : sim.graph().systems()) h << ",ms_" << s->name();
    h << ",ms_spatial_sort\n";  // the engine's re-sort before the systems (Simulation::last_sort_seconds)
    return h.str();
}

Recorder::Recorder(std::filesystem::path dir, const Simulation& sim, Open)
    : m_dir(std::move(dir)), m_probes(sim.world().scene.probes) {
    check_surface_formats(sim.world());
    std::filesystem::create_directories(m_dir);
    reserve_space();
    // The probes' folder now, not at the first write: on a file system out of inodes the run
    // stops here, before its first step, rather than after it (the reserve holds bytes, not inodes).
    try {  // this constructor's own throw runs no destructor: the reserve is removed here
        if (!sim.world().scene.probes.empty()) std::filesystem::create_directories(m_dir / "probes");
    } catch (...) {
        release_reserve();
        throw;
    }
    m_t0 = std::chrono::steady_clock::now();
}

void Recorder::check_resume(const std::filesystem::path& dir, const Simulation& sim, const nlohmann::json& st) {
    const std::uint64_t bytes = st.at("stats_bytes").get<std::uint64_t>();
    const auto csv = dir / "stats.csv";
    std::error_code ec;
    const auto have = std::filesystem::file_size(csv, ec);
    if (ec) return;
    if (have < bytes)
        throw InputError(csv.string() + ": holds " + std::to_string(have) + " bytes, expected at least the " +
                         std::to_string(bytes) + " written before the checkpoint (resume into another --out)");
    // Rows appended under another header would be misread by every tool (an older engine wrote
    // the file, or another recipe with other systems).
    std::string first;
    std::getline(std::ifstream(csv), first);
    if (first + '\n' != header(sim))
        throw InputError(csv.string() + ": its columns differ from this run's (written by another engine version "
                         "or recipe?); expected the header\n  " + header(sim) + "resume into another --out");
}

// Both public constructors delegate: the object exists once Recorder(dir, sim, Open) returns, so
// a throw from their bodies runs ~Recorder, which removes the reserve.
Recorder::Recorder(std::filesystem::path dir, const Simulation& sim) : Recorder(std::move(dir), sim, Open{}) {
    write_scene(m_dir, sim.world().scene);
    m_pending = header(sim);
}

Recorder::Recorder(std::filesystem::path dir, const Simulation& sim, const nlohmann::json& st)
    : Recorder(std::move(dir), sim, Open{}) {
    m_frame = st.at("frame").get<std::size_t>();
    m_start_steps = sim.steps();
    m_first_frame = st.value("first_frame", std::size_t(0));  // absent before 2026-12-06: 0
    m_boundary_written = std::filesystem::exists(m_dir / "boundary" / "walls.vtu") ||
                         std::filesystem::exists(m_dir / "boundary" / "walls.ply") ||
                         std::filesystem::exists(m_dir / "boundary" / "walls.bgeo");
    if (const auto it = st.find("frame_times"); it != st.end()) {
        m_frame_times = it->get<std::vector<double>>();
    } else {  // a checkpoint of an earlier version: the nominal times
        for (std::size_t k = 0; k < m_frame; ++k)
            m_frame_times.push_back(double(k) / sim.world().scene.simulation.frame_rate);
    }
    if (m_frame_times.size() != m_frame)
        throw InputError("the checkpoint's recorder holds " + std::to_string(m_frame_times.size()) +
                         " frame times for " + std::to_string(m_frame) + " frames");
    m_next_frame_time = st.at("next_frame_time").get<double>();
    m_collisions = st.at("collisions").get<std::uint64_t>();
    m_active_fraction_sum = st.at("active_fraction_sum").get<double>();
    m_dt_min = st.at("dt_min").get<double>();
    m_dt_max = st.at("dt_max").get<double>();
    m_rho_err_max = st.at("rho_err_max").get<double>();
    m_steps = st.at("steps").get<std::uint64_t>();
    m_rho_err_avg_max = st.at("rho_err_avg_max").get<double>();
    for (const auto& [name, v] : st.at("counter_sums").items()) m_counter_sums[name] = v.get<double>();
    for (const auto& [name, v] : st.at("counter_per_fluid_sums").items()) m_counter_per_fluid_sums[name] = v.get<double>();
    for (const auto& f : st.at("fronts")) m_fronts.emplace_back(f.at(0).get<double>(), f.at(1).get<double>());
    // The probe series so far (checkpoints of earlier versions have none: their probes restart
    // at the resume time).
    if (const auto it = st.find("probes"); it != st.end()) m_probes.restore(*it);
    const std::uint64_t bytes = st.at("stats_bytes").get<std::uint64_t>();
    check_resume(m_dir, sim, st);
    const auto csv = m_dir / "stats.csv";
    std::error_code ec;
    const auto have = std::filesystem::file_size(csv, ec);
    if (ec) {
        // A new directory: stats.csv starts at the checkpoint's step, and so do the frames (the
        // collections list only those this folder holds).
        m_pending = header(sim);
        m_first_frame = m_frame;
    } else {
        m_stats_bytes = bytes;
    }
    // The folder is this run's (check_resume above; sph-run calls it before it takes the folder,
    // so a refused resume leaves another run's folder as it was): only now is anything replaced.
    write_scene(m_dir, sim.world().scene);
    if (!ec && have > bytes) {
        // Rows written after the checkpoint will be written again: keep only the prefix.
        AtomicFile f(csv);
        f.copy_prefix(csv, bytes);
        f.commit();
    }
    m_t0 = std::chrono::steady_clock::now();
}

nlohmann::json Recorder::state() {
    flush_stats();
    return {{"frame", m_frame},
            {"first_frame", m_first_frame},
            {"frame_times", m_frame_times},
            {"next_frame_time", m_next_frame_time},
            {"collisions", m_collisions},
            {"active_fraction_sum", m_active_fraction_sum},
            {"dt_min", m_dt_min},
            {"dt_max", m_dt_max},
            {"rho_err_max", m_rho_err_max},
            {"steps", m_steps},
            {"rho_err_avg_max", m_rho_err_avg_max},
            {"counter_sums", m_counter_sums},
            {"counter_per_fluid_sums", m_counter_per_fluid_sums},
            {"fronts", m_fronts},
            {"stats_bytes", m_stats_bytes},
            {"probes", m_probes.state()}};
}

void Recorder::begin(const Simulation& sim) {
    m_probes.sample_due(sim.world());
    if (sim.world().scene.simulation.frame_rate > 0) write_frame(sim);
}

void Recorder::write_frame(const Simulation& sim) {
    const World& w = sim.world();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu", m_frame);
    if (w.scene.output.writes_particles()) sph::write_frame(m_dir / "frames" / name, w);
    std::snprintf(name, sizeof name, "surface_%05zu", m_frame);
    write_surface(w, name);
    // The walls and obstacles once (boundary/walls.*), the moving bodies with every frame
    // (boundary/moving_NNNNN.*), so a render shows them beside the fluid; frames/ holds only
    // the fluid's frames.
    if (w.static_boundary_end > 0 && !m_boundary_written) {
        write_boundary(m_dir / "boundary" / "walls", w, 0, w.static_boundary_end, 0.0);  // it never moves
        m_boundary_written = true;
    }
    if (w.boundary.size() > w.static_boundary_end) {
        std::snprintf(name, sizeof name, "moving_%05zu", m_frame);
        write_boundary(m_dir / "boundary" / name, w, w.static_boundary_end, w.boundary.size(), sim.time());
    }
    m_frame_times.push_back(sim.time());
    ++m_frame;
    write_collection(sim.world());
    m_next_frame_time = double(m_frame) / sim.world().scene.simulation.frame_rate;
    flush_stats();
}

void Recorder::write_surface(const World& w, const char* name) {
    const bool vdb = w.scene.output.writes(FrameFormat::Vdb), mesh = w.scene.output.writes(FrameFormat::Mesh);
    if (!vdb && !mesh) return;
    const auto t0 = std::chrono::steady_clock::now();
    const double r = w.physics.particle_radius;
    const FluidSurface surface(w.fluid.store.get(comp::position), r, w.scene.output.surface.resolve(r));
    if (vdb) surface.write_vdb(m_dir / "surface" / (std::string(name) + ".vdb"), w.clock.t);
    if (mesh) write_mesh_ply(m_dir / "surface" / (std::string(name) + ".ply"), surface.mesh(), w.clock.t);
    m_surface_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++m_surface_frames;
}

void Recorder::write_collection(const World& w) const {
    // A ParaView collection of the .vtu frames with the time each was written at (the first step
    // that reached k / frame_rate), so ParaView's time is the simulated time.
    if (!w.scene.output.writes(FrameFormat::Vtu)) return;
    const auto collection = [&](const char* stem, const char* file) {
        std::ostringstream x;
        x << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
             "  <Collection>\n"
          << std::setprecision(17);
        for (std::size_t k = m_first_frame; k < m_frame_times.size(); ++k) {
            char name[48];
            std::snprintf(name, sizeof name, "%s_%05zu.vtu", stem, k);  // relative to the run folder
            x << "    <DataSet timestep=\"" << m_frame_times[k] << "\" group=\"\" part=\"0\" file=\"" << name
              << "\"/>\n";
        }
        x << "  </Collection>\n</VTKFile>\n";
        write_file_atomic(m_dir / file, x.str());
    };
    collection("frames/frame", "frames.pvd");
    if (w.boundary.size() > w.static_boundary_end) collection("boundary/moving", "boundary_moving.pvd");
}

bool Recorder::front_due(const World& w) const {
    return m_fronts.size() < 3 && w.clock.t >= 0.25 * double(m_fronts.size() + 1) * w.scene.simulation.end_time - 1e-9;
}

bool Recorder::frame_due(const World& w) const {
    return w.scene.simulation.frame_rate > 0 && w.clock.t >= m_next_frame_time - 1e-9;
}

bool Recorder::reads_particles(const Simulation& sim) const {
    // after_step reads particles only through front_x, sample_due and write_frame.
    const World& w = sim.world();
    if (sim.last().rolled_back) return false;
    return front_due(w) || frame_due(w) || m_probes.any_due(w.clock.t);
}

void Recorder::after_step(const Simulation& sim) {
    const World& w = sim.world();
    const StepRecord& rec = sim.last();
    const StepStats& st = w.stats;
    const auto c = [&](std::string_view name) { return w.counter_value(name); };
    const std::uint64_t updated = c("updated"), active = c("active");
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_t0).count();
    std::ostringstream row;
    row << std::setprecision(9) << rec.step << ',' << rec.t << ',' << rec.dt << ',' << updated << ','
        << (updated ? double(c("neighbour_pairs")) / double(updated) : 0.0) << ',' << st.rho_err_avg << ','
        << st.rho_err_max << ',' << st.v_max << ',' << st.a_max << ',' << c("collisions") << ',' << active << ','
        << (w.fluid.size() ? double(active) / double(w.fluid.size()) : 0.0);
    for (const char* name : {"neighbour_searches", "force_evaluations", "boundary_contributions",
                             "propagation_updates", "iterations", "boundary_active"})
        row << ',' << c(name);
    row << ',' << int(rec.rolled_back) << ',' << st.v_mean << ',' << int(st.whole_fluid);
    for (const auto& name : extra_counters(w)) row << ',' << c(name);
    row << ',' << wall;
    const auto& g = sim.graph();
    row << std::setprecision(4);
    for (std::size_t i = 0; i < g.systems().size(); ++i) row << ',' << g.last_seconds(i) * 1e3;
    row << ',' << sim.last_sort_seconds() * 1e3 << '\n';
    m_sort_seconds += sim.last_sort_seconds();
    m_pending += row.str();
    m_collisions += c("collisions");
    if (rec.rolled_back) return;  // a discarded step (rollback) counts in no statistic
    if (w.fluid.size()) m_active_fraction_sum += double(active) / double(w.fluid.size());
    // Per-particle averages and sums of every counter over the kept steps (System::summarise).
    for (const auto& [name, v] : w.counters) {
        m_counter_sums[name] += double(v);
        if (w.fluid.size()) m_counter_per_fluid_sums[name] += double(v) / double(w.fluid.size());
    }
    // The fluid's average: over the steps whose statistics cover every row (binned's other steps
    // average their due rows only, a few at an impact can read 20x the fluid's).
    if (st.whole_fluid) m_rho_err_avg_max = std::max(m_rho_err_avg_max, st.rho_err_avg);
    // The step the conditions allowed (a last step clipped to the end time is not a minimum).
    const double dt_taken = rec.dt_stable > 0 ? rec.dt_stable : rec.dt;
    m_dt_min = m_steps ? std::min(m_dt_min, dt_taken) : dt_taken;
    m_dt_max = std::max(m_dt_max, dt_taken);
    m_rho_err_max = std::max(m_rho_err_max, st.rho_err_max);
    ++m_steps;
    while (front_due(w)) m_fronts.emplace_back(w.clock.t, front_x(w));
    m_probes.sample_due(w);
    if (frame_due(w)) {
        write_frame(sim);
    } else if (m_pending.size() > kMaxPendingStats) {
        flush_stats();
    }
}

void Recorder::flush_stats() {
    if (m_pending.empty()) return;
    const auto csv = m_dir / "stats.csv";
    AtomicFile f(csv);
    if (m_stats_bytes > 0) f.copy_prefix(csv, m_stats_bytes);
    f.write(m_pending);
    f.commit();
    m_stats_bytes += m_pending.size();
    m_pending.clear();
    m_probes.write(m_dir);
}

nlohmann::json Recorder::finish(const Simulation& sim, double wall_seconds, int threads) {
    flush_stats();
    const World& w = sim.world();
    const auto& g = sim.graph();
    nlohmann::json j;
    j["scene"] = w.scene.name;
    j["method"] = to_string(w.scene.simulation.method);
    j["stepping"] = to_string(w.scene.simulation.stepping.mode);
    if (w.scene.simulation.stepping.mode == SteppingMode::Individual)
        j["activation"] = to_string(w.scene.simulation.stepping.activation);
    j["fluid_particles"] = w.fluid.size();
    j["boundary_particles"] = w.boundary.size();
    j["simulated_time_s"] = sim.time();
    j["steps"] = sim.steps();
    j["wall_time_s"] = wall_seconds;
    // Process CPU time (user + system): on a shared machine it varies far less than the wall
    // time when other processes compete for the cores.
    {
        rusage u{};
        getrusage(RUSAGE_SELF, &u);
        j["cpu_time_s"] = double(u.ru_utime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec) +
                          double(u.ru_stime.tv_sec) + 1e-6 * double(u.ru_stime.tv_usec);
    }
    j["threads"] = threads;
    // The instruction set of the pair loops: the dispatched target, or "scalar" (simulation.simd).
    j["simd"] = w.physics.simd ? simd_target() : std::string("scalar");
    // Over the steps this process took (wall_seconds is its own; a resumed run took fewer).
    const double fps =
        wall_seconds > 0 ? double(w.fluid.size()) * double(sim.steps() - m_start_steps) / wall_seconds : 0.0;
    j["fluid_particle_steps_per_s"] = fps;
    j["avg_dt_s"] = sim.steps() ? sim.time() / double(sim.steps()) : 0.0;
    j["min_dt_s"] = m_dt_min;
    j["max_dt_s"] = m_dt_max;
    j["avg_active_fraction"] = m_steps ? m_active_fraction_sum / double(m_steps) : 0.0;
    j["max_density_error"] = m_rho_err_max;
    j["max_avg_density_error"] = m_rho_err_avg_max;
    j["shocks"] = w.clock.rollbacks;
    j["kept_steps"] = m_steps;
    // The step conditions the run used (docs/usage.md, summary.json): tools/stepping_bound.py
    // reads them with stats.csv's dt and active_fraction.
    {
        const SteppingParams& sp = w.scene.simulation.stepping;
        j["stepping_params"] = {{"lambda_v", sp.lambda_v}, {"lambda_f", sp.lambda_f}, {"acoustic", sp.acoustic},
                                {"lambda_c", sp.lambda_c}, {"dt_max", sp.dt_max},   {"dt_min", sp.dt_min}};
    }
    // What each system adds (a method's own figures, System::summarise).
    RunTotals totals;
    totals.kept_steps = m_steps;
    totals.counter_sums = &m_counter_sums;
    totals.counter_per_fluid_sums = &m_counter_per_fluid_sums;
    for (const auto& s : g.systems()) s->summarise(w, totals, j);
    j["peak_memory_bytes"] = peak_memory_bytes();
    const std::size_t bytes = sim.particle_bytes();
    j["particle_data_bytes"] = bytes;
    j["bytes_per_fluid_particle"] = w.fluid.size() ? double(bytes) / double(w.fluid.size()) : 0.0;
    // Where those bytes go (boundary parts are shared out over the fluid particles too).
    nlohmann::json parts = nlohmann::json::object();
    for (const auto& [name, b] : sim.memory_parts())
        if (b > 0) parts[name] = w.fluid.size() ? double(b) / double(w.fluid.size()) : 0.0;
    j["bytes_per_fluid_particle_by_part"] = parts;
    j["peak_memory_per_fluid_particle"] = w.fluid.size() ? double(peak_memory_bytes()) / double(w.fluid.size()) : 0.0;
    j["physics"] = {{"particle_radius", w.physics.particle_radius},
                    {"support_radius", w.physics.h},
                    {"mass", w.physics.mass},
                    {"speed_of_sound", w.physics.speed_of_sound},
                    {"fluid_height", w.physics.fluid_height},
                    {"rest_density", w.physics.rest_density},
                    {"artificial_viscosity", w.physics.viscosity},
                    {"boundary_viscosity", w.physics.boundary_viscosity},
                    {"density", w.physics.continuity ? "continuity" : "summation"},
                    {"density_diffusion", w.physics.density_diffusion},
                    {"kinematic_viscosity", w.physics.kinematic_viscosity},
                    {"wall_pressure", w.physics.extrapolated_wall_pressure ? "extrapolated" : "mirrored"}};
    if (const auto& wave = w.scene.standing_wave) {
        // Linear theory for the wave the scene gives (engine/data/scene.hpp standing_wave_theory):
        // what sph-study compares the measured period and decay with.
        const WaveTheory th = standing_wave_theory(w.scene);
        j["standing_wave"] = {{"amplitude", wave->amplitude}, {"mode", wave->mode}, {"at", wave->at},
                              {"period_theory_s", th.period}, {"decay_theory_per_s", th.decay}};
    }
    j["frames"] = m_frame - m_first_frame;  // in this folder (a resume into a new one starts later)
    if (m_surface_frames > 0) {
        // The surface's cost per frame, also in steps of this run (an average step's time in
        // the systems).
        const double per_frame = m_surface_seconds / double(m_surface_frames);
        double systems_s = 0;
        for (std::size_t i = 0; i < g.systems().size(); ++i) systems_s += g.total_seconds(i);
        const double per_step = sim.steps() ? systems_s / double(sim.steps()) : 0.0;
        j["surface"] = {{"frames", m_surface_frames},
                        {"seconds", m_surface_seconds},
                        {"seconds_per_frame", per_frame},
                        {"steps_per_frame", per_step > 0 ? per_frame / per_step : 0.0}};
    }
    j["boundary_collisions_total"] = m_collisions;
    j["front_x_m"] = front_x(w);
    // The front at a quarter, half and three quarters of the end time (the first step ending
    // at or after each), to compare modes while the surge is still running.
    nlohmann::json fronts = nlohmann::json::array();
    for (const auto& [t, x] : m_fronts) fronts.push_back({{"t", t}, {"x", x}});
    j["front_x_m_at"] = fronts;
    double total = 0;
    for (std::size_t i = 0; i < g.systems().size(); ++i) total += g.total_seconds(i);
    nlohmann::json systems = nlohmann::json::array();
    for (std::size_t i = 0; i < g.systems().size(); ++i)
        systems.push_back({{"name", g.systems()[i]->name()},
                           {"seconds", g.total_seconds(i)},
                           {"share", total > 0 ? g.total_seconds(i) / total : 0.0}});
    j["systems"] = systems;
    j["systems_total_s"] = total;
    j["spatial_sort_s"] = m_sort_seconds;  // outside the systems: the re-sorts of the particle columns
    if (!m_interrupted.empty()) j["interrupted"] = {{"by", m_interrupted}, {"t", sim.time()}, {"step", sim.steps()}};
    if (!m_failed.empty()) j["failed"] = {{"reason", m_failed}, {"t", sim.time()}, {"step", sim.steps()}};
    if (!m_output_failed.empty())
        j["output_failed"] = {{"reason", m_output_failed}, {"t", sim.time()}, {"step", sim.steps()}};
    write_file_atomic(m_dir / "summary.json", j.dump(2) + "\n");
    if (m_output_failed.empty()) release_reserve();
    return j;
}

}  // namespace sph
