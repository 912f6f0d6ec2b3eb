#pragma once
/// @file recorder.hpp
/// @brief Writes a run's outputs into one directory: stats.csv (a row per step), VTU frames at
/// the scene's frame rate, probe series (probes/<name>.csv) and summary.json at the end. Files are written atomically; the CSV
/// is rewritten whole at each frame boundary, so a killed run leaves a complete prefix.
#include <chrono>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "engine/probes.hpp"
#include "engine/simulation.hpp"

namespace sph {

class Recorder {
public:
    Recorder(std::filesystem::path dir, const Simulation& sim);
    /// @brief Called after every step: appends the stats row, writes a frame when due.
    void after_step(const Simulation& sim);
    /// @brief Writes the initial frame (t = 0).
    void begin(const Simulation& sim);
    /// @brief Flushes stats.csv and writes summary.json; returns the summary.
    nlohmann::json finish(const Simulation& sim, double wall_seconds, int threads);

    const std::filesystem::path& dir() const { return m_dir; }
    std::size_t frames_written() const { return m_frame; }

private:
    void write_frame(const Simulation& sim);
    void flush_stats();

    std::filesystem::path m_dir;
    ProbeSet m_probes;  ///< the scene's probes, written to probes/<name>.csv with stats.csv
    std::string m_csv;
    std::size_t m_frame = 0;
    std::uint64_t m_collisions = 0;
    double m_active_fraction_sum = 0;  ///< sum over steps of active / fluid particles
    double m_dt_min = 0, m_dt_max = 0, m_rho_err_max = 0;
    std::uint64_t m_steps = 0;
    double m_next_frame_time = 0;
    std::chrono::steady_clock::time_point m_t0;
};

}  // namespace sph
