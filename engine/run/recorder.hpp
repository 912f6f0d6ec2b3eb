#pragma once
/// @file recorder.hpp
/// @brief Writes a run's outputs into one directory: stats.csv (a row per step), frames at
/// the scene's frame rate (frames/frame_NNNNN.vtu/.bgeo/.ply), probe series (probes/<name>.csv, written with stats.csv)
/// and summary.json at the end.
/// Every file is replaced atomically (AtomicFile). stats.csv is committed at each frame, at
/// each checkpoint, whenever 4 MiB of rows are pending, and at the end: the new file is the
/// committed prefix copied from the old one plus the pending rows, so memory stays bounded
/// and a killed run leaves a complete prefix of whole rows.
/// A full disk does not lose the run: the recorder keeps 5 MiB in reserve (.sph-reserve, made
/// before the run starts) and, when an output cannot be written, salvage() frees it and saves
/// what was computed into that room: the pending stats.csv rows, summary.json (marked
/// "output_failed") and the probe series.
#include <chrono>
#include <map>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/run/probes.hpp"
#include "engine/run/simulation.hpp"

namespace sph {

/// @brief The front: the largest x of a fluid particle with at least 4 fluid neighbours.
double front_x(const World& w);

class Recorder {
public:
    Recorder(std::filesystem::path dir, const Simulation& sim);
    /// @brief Continues a run from a checkpoint: `state` is what state() returned then; the
    /// first stats_bytes bytes of dir/stats.csv are kept (a fresh stats.csv is started at the
    /// checkpoint's step when the directory has none).
    /// check_resume's refusals throw as there, the reserve removed; a state without the keys
    /// state() writes throws nlohmann::json::exception (sph-run names the checkpoint).
    Recorder(std::filesystem::path dir, const Simulation& sim, const nlohmann::json& state);
    /// @brief Whether a run resumed from `state` may continue in `dir`, reading only: throws
    /// InputError naming dir/stats.csv when it holds fewer bytes than were written before the
    /// checkpoint or another header (another run's folder). A folder without stats.csv passes.
    static void check_resume(const std::filesystem::path& dir, const Simulation& sim, const nlohmann::json& state);
    ~Recorder();  ///< removes the reserve whatever ended the run
    Recorder(const Recorder&) = delete;
    Recorder& operator=(const Recorder&) = delete;
    /// @brief Called after every step: appends the stats row, writes a frame when due.
    void after_step(const Simulation& sim);
    /// @brief true when after_step at the simulation's present time reads particle columns (a
    /// frame, a probe sample or a front is due): a caller that runs the simulation without
    /// synchronised observers (Simulation::set_synchronise_observers) synchronises then.
    bool reads_particles(const Simulation& sim) const;
    /// @brief Writes the initial frame (t = 0).
    void begin(const Simulation& sim);
    /// @brief Flushes stats.csv and writes summary.json; returns the summary.
    nlohmann::json finish(const Simulation& sim, double wall_seconds, int threads);

    const std::filesystem::path& dir() const { return m_dir; }
    /// Frames in this run's folder (a run resumed into a new folder holds those from the
    /// checkpoint on).
    std::size_t frames_written() const { return m_frame - m_first_frame; }
    /// @brief Commits stats.csv, then returns everything needed to continue the outputs
    /// exactly (frame counter, next frame time, summary accumulators, committed CSV bytes).
    nlohmann::json state();
    /// @brief Marks the run as stopped before its end (summary.json "interrupted": the signal).
    void set_interrupted(std::string reason) { m_interrupted = std::move(reason); }
    /// @brief Marks the run as failed (summary.json "failed": the simulation's error).
    void set_failed(std::string reason) { m_failed = std::move(reason); }
    /// @brief Commits the pending stats.csv rows.
    void flush_stats();
    /// @brief After an output failed (OutputError: disk full, ...): frees the reserve, appends
    /// the pending stats.csv rows in place (the committed file is intact: every write is atomic),
    /// writes summary.json marked "output_failed" with `reason`, and the probes. Returns one line
    /// per output saved or not ("stats.csv: 1234 rows up to t = ...", "summary.json: ...").
    std::vector<std::string> salvage(const Simulation& sim, const std::string& reason, double wall_seconds,
                                     int threads);

private:
    struct Open {};
    /// What both constructors do first: the folder, its reserve and (with probes) probes/.
    Recorder(std::filesystem::path dir, const Simulation& sim, Open);
    /// after_step's particle reads, one predicate each (reads_particles is their union).
    bool front_due(const World& w) const;
    bool frame_due(const World& w) const;
    std::string m_interrupted;  ///< why the run stopped early ("" when it reached its end)
    std::string m_failed;  ///< set_failed's reason ("" for a run that did not fail)
    std::string m_output_failed;  ///< the output error salvage() was called for
    void reserve_space();
    void release_reserve();
    void write_frame(const Simulation& sim);
    /// surface/surface_NNNNN.vdb and/or .ply (formats vdb, mesh) from one level set.
    void write_surface(const World& w, const char* name);
    double m_surface_seconds = 0;      ///< wall time spent building and writing surfaces (this process)
    std::uint64_t m_surface_frames = 0;  ///< surfaces built (this process)
    /// frames.pvd (and boundary_moving.pvd): every .vtu frame so far with its simulated time (ParaView).
    void write_collection(const World& w) const;
    static std::string header(const Simulation& sim);

    std::filesystem::path m_dir;
    ProbeSet m_probes;  ///< the scene's probes, written to probes/<name>.csv with stats.csv
    std::string m_pending;           ///< rows not yet committed to stats.csv
    std::uint64_t m_stats_bytes = 0;  ///< bytes of stats.csv committed so far
    std::size_t m_frame = 0;        ///< the next frame's index (frames since the run began)
    std::size_t m_first_frame = 0;  ///< the first frame this folder holds
    std::int64_t m_start_steps = 0;  ///< steps taken before this process (a resumed run's checkpoint)
    std::vector<double> m_frame_times;  ///< simulated time of each frame written
    bool m_boundary_written = false;    ///< frames/boundary.* (the static boundary) exists
    std::uint64_t m_collisions = 0;
    double m_active_fraction_sum = 0;  ///< sum over steps of active / fluid particles
    double m_sort_seconds = 0;         ///< wall seconds of the re-sorts (Simulation::last_sort_seconds) this process
    double m_dt_min = 0, m_dt_max = 0, m_rho_err_max = 0;
    std::uint64_t m_steps = 0;          ///< kept steps (a rolled-back step is not counted)
    double m_rho_err_avg_max = 0;
    /// Over kept steps: sum of each counter, and of each counter divided by the fluid count.
    std::map<std::string, double, std::less<>> m_counter_sums, m_counter_per_fluid_sums;
    double m_next_frame_time = 0;
    std::vector<std::pair<double, double>> m_fronts;  ///< (t, front x) at 1/4, 1/2, 3/4 of the end
    std::chrono::steady_clock::time_point m_t0;
};

}  // namespace sph
