#include "engine/recorder.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <iomanip>
#include <sstream>

#include "engine/components.hpp"
#include "engine/io.hpp"

namespace sph {

Recorder::Recorder(std::filesystem::path dir, const Simulation& sim)
    : m_dir(std::move(dir)), m_probes(sim.world().scene.probes) {
    std::filesystem::create_directories(m_dir);
    std::ostringstream h;
    h << "step,t,dt,updated,neighbours_per_particle,rho_err_avg,rho_err_max,v_max,a_max,collisions,"
         "active,active_fraction,neighbour_searches,force_evaluations,boundary_contributions,"
         "propagation_updates,wall_s";
    for (const auto& s : sim.graph().systems()) h << ",ms_" << s->name();
    h << '\n';
    m_csv = h.str();
    m_t0 = std::chrono::steady_clock::now();
}

void Recorder::begin(const Simulation& sim) {
    m_probes.sample_due(sim.world());
    if (sim.world().scene.simulation.frame_rate > 0) write_frame(sim);
}

void Recorder::write_frame(const Simulation& sim) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.vtu", m_frame);
    write_vtu(m_dir / "frames" / name, sim.world(), sim.world().scene.output.attributes);
    ++m_frame;
    m_next_frame_time = double(m_frame) / sim.world().scene.simulation.frame_rate;
    flush_stats();
}

void Recorder::after_step(const Simulation& sim) {
    const World& w = sim.world();
    const StepState& s = w.step;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_t0).count();
    std::ostringstream row;
    row << std::setprecision(9) << (s.step - 1) << ',' << s.t - s.dt << ',' << s.dt << ',' << s.updated << ','
        << (s.updated ? double(s.neighbour_pairs) / double(s.updated) : 0.0) << ',' << s.rho_err_avg << ','
        << s.rho_err_max << ',' << s.v_max << ',' << s.a_max << ',' << s.collisions << ',' << s.active << ','
        << (w.fluid.size() ? double(s.active) / double(w.fluid.size()) : 0.0) << ',' << s.neighbour_searches << ','
        << s.force_evaluations << ',' << s.boundary_contributions << ',' << s.propagation_updates << ',' << wall;
    const auto& g = sim.graph();
    row << std::setprecision(4);
    for (std::size_t i = 0; i < g.systems().size(); ++i) row << ',' << g.last_seconds(i) * 1e3;
    row << '\n';
    m_csv += row.str();
    m_collisions += s.collisions;
    if (w.fluid.size()) m_active_fraction_sum += double(s.active) / double(w.fluid.size());
    // The step the conditions allowed (a last step clipped to the end time is not a minimum).
    const double dt_taken = s.dt_stable > 0 ? s.dt_stable : s.dt;
    m_dt_min = m_steps ? std::min(m_dt_min, dt_taken) : dt_taken;
    m_dt_max = std::max(m_dt_max, dt_taken);
    m_rho_err_max = std::max(m_rho_err_max, s.rho_err_max);
    ++m_steps;
    m_probes.sample_due(w);
    const double rate = w.scene.simulation.frame_rate;
    if (rate > 0 && s.t >= m_next_frame_time - 1e-9) write_frame(sim);
}

void Recorder::flush_stats() {
    write_file_atomic(m_dir / "stats.csv", m_csv);
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
    j["fluid_particles"] = w.fluid.size();
    j["boundary_particles"] = w.boundary.size();
    j["simulated_time_s"] = sim.time();
    j["steps"] = sim.steps();
    j["wall_time_s"] = wall_seconds;
    j["threads"] = threads;
    const double fps = wall_seconds > 0 ? double(w.fluid.size()) * double(sim.steps()) / wall_seconds : 0.0;
    j["fluid_particle_steps_per_s"] = fps;
    j["avg_dt_s"] = sim.steps() ? sim.time() / double(sim.steps()) : 0.0;
    j["min_dt_s"] = m_dt_min;
    j["max_dt_s"] = m_dt_max;
    j["avg_active_fraction"] = m_steps ? m_active_fraction_sum / double(m_steps) : 0.0;
    j["max_density_error"] = m_rho_err_max;
    j["peak_memory_bytes"] = peak_memory_bytes();
    const std::size_t bytes = sim.particle_bytes();
    j["particle_data_bytes"] = bytes;
    j["bytes_per_fluid_particle"] = w.fluid.size() ? double(bytes) / double(w.fluid.size()) : 0.0;
    j["peak_memory_per_fluid_particle"] = w.fluid.size() ? double(peak_memory_bytes()) / double(w.fluid.size()) : 0.0;
    j["physics"] = {{"particle_radius", w.physics.particle_radius},
                    {"support_radius", w.physics.h},
                    {"mass", w.physics.mass},
                    {"speed_of_sound", w.physics.speed_of_sound},
                    {"fluid_height", w.physics.fluid_height}};
    j["frames"] = m_frame;
    j["boundary_collisions_total"] = m_collisions;
    // Front at the end: the largest x of a fluid particle with at least 4 fluid neighbours
    // (so a lone droplet thrown ahead is not the front), in metres.
    {
        const auto x = w.fluid.store.get(comp::position);
        double front = -std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < x.size(); ++i)
            if (i < w.fluid_neighbours.count.size() && w.fluid_neighbours.count[i] >= 4)
                front = std::max(front, double(x[i].x()));
        j["front_x_m"] = std::isfinite(front) ? front : 0.0;
    }
    double total = 0;
    for (std::size_t i = 0; i < g.systems().size(); ++i) total += g.total_seconds(i);
    nlohmann::json systems = nlohmann::json::array();
    for (std::size_t i = 0; i < g.systems().size(); ++i)
        systems.push_back({{"name", g.systems()[i]->name()},
                           {"seconds", g.total_seconds(i)},
                           {"share", total > 0 ? g.total_seconds(i) / total : 0.0}});
    j["systems"] = systems;
    j["systems_total_s"] = total;
    write_file_atomic(m_dir / "summary.json", j.dump(2) + "\n");
    return j;
}

}  // namespace sph
