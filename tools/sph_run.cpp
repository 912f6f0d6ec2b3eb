// sph-run: runs one scene and writes stats.csv, summary.json and VTU frames.
// Exit codes: 0 ok, 2 bad input, 3 simulation failed.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <iostream>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "engine/errors.hpp"
#include "engine/recorder.hpp"
#include "systems/methods/wcsph.hpp"

namespace {

std::string format_seconds(double s) {
    char buf[32];
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%.1fs", s);
    else
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    return buf;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"sph-run: simulate one SPH scene and write its outputs"};
    app.set_version_flag("--version", std::string("sph-run ") + SPH_VERSION);
    std::string scene_file, mode, out_dir, graph_file;
    double end_time = -1, dt = -1, scale = -1;
    int threads = 0;
    std::vector<std::string> sets;
    bool quiet = false, no_frames = false, list_modes = false;
    app.add_option("scene", scene_file, "Scene file (JSON)")->required();
    app.add_option("--mode", mode, "Stepping mode: constant | global | individual");
    app.add_option("--end", end_time, "Simulated end time in seconds (overrides simulation.end_time)");
    app.add_option("--dt", dt, "Time step in seconds (constant mode; first step of global)");
    app.add_option("--scale", scale, "Particle-count multiplier (overrides simulation.scale)");
    app.add_option("--out", out_dir, "Output directory (default out/<scene name>)");
    app.add_option("--threads", threads, "Worker threads (default: all cores)");
    app.add_option("--graph", graph_file, "Write the system graph as Graphviz dot to this file");
    app.add_option("--set", sets, "Override a scene value: --set simulation.stepping.lambda_v=0.1 (repeatable)");
    app.add_flag("--no-frames", no_frames, "Write no particle frames");
    app.add_flag("-q,--quiet", quiet, "Log warnings and errors only");
    app.add_flag("--list-modes", list_modes,
                 "Print every 'method mode' pair this scene loads with (one a line; sph-study runs them) and exit");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }
    if (quiet) spdlog::set_level(spdlog::level::warn);

    std::unique_ptr<sph::Simulation> sim;
    std::unique_ptr<sph::Recorder> recorder;
    try {
        std::vector<std::pair<std::string, nlohmann::json>> overrides;
        for (const auto& s : sets) overrides.push_back(sph::parse_override(s));
        if (!mode.empty()) overrides.emplace_back("/simulation/stepping/mode", mode);
        if (end_time >= 0 || app.count("--end")) overrides.emplace_back("/simulation/end_time", end_time);
        if (dt >= 0 || app.count("--dt")) overrides.emplace_back("/simulation/stepping/dt", dt);
        if (scale >= 0 || app.count("--scale")) overrides.emplace_back("/simulation/scale", scale);
        if (no_frames) overrides.emplace_back("/simulation/frame_rate", 0.0);
        if (threads < 0) throw sph::InputError("--threads: found " + std::to_string(threads) + ", expected a count >= 0");
        for (const auto& [path, value] : overrides)
            spdlog::info("command line sets {} = {}", path, value.dump());

        if (list_modes) {  // every pair the loader accepts for this scene (tools/sph_study.py)
            sph::load_scene(scene_file, overrides);  // the scene itself must load
            for (const auto& method : sph::method_names())
                for (const auto& m : sph::stepping_mode_names()) {
                    auto o = overrides;
                    o.emplace_back("/simulation/method", method);
                    o.emplace_back("/simulation/stepping/mode", m);
                    try {
                        sph::load_scene(scene_file, o);
                        std::printf("%s %s\n", method.c_str(), m.c_str());
                    } catch (const sph::SceneError&) {
                    }
                }
            return 0;
        }
        const sph::Scene scene = sph::load_scene(scene_file, overrides);
        const int nthreads = threads > 0 ? threads : tbb::info::default_concurrency();
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(nthreads));

        const auto t_setup = std::chrono::steady_clock::now();
        sim = sph::make_simulation(scene);
        const auto& w = sim->world();
        spdlog::info("scene '{}' from {}: {} fluid + {} boundary particles, r = {} m, h = {} m, c_s = {:.3g} m/s, "
                     "mass = {:.4g} kg, method {} / {}, end {} s, {} thread(s), set-up {:.2f} s",
                     scene.name, scene_file, w.fluid.size(), w.boundary.size(), w.physics.particle_radius,
                     w.physics.h, w.physics.speed_of_sound, w.physics.mass, sph::to_string(scene.simulation.method),
                     sph::to_string(scene.simulation.stepping.mode), scene.simulation.end_time, nthreads,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t_setup).count());
        if (!graph_file.empty()) {
            sim->graph().write_dot(graph_file);
            spdlog::info("system graph written to {}", graph_file);
        }
        const std::filesystem::path out = out_dir.empty() ? std::filesystem::path("out") / scene.name : std::filesystem::path(out_dir);
        recorder = std::make_unique<sph::Recorder>(out, *sim);
        recorder->begin(*sim);

        const bool tty = ::isatty(STDERR_FILENO);
        const auto t0 = std::chrono::steady_clock::now();
        auto last_report = t0;
        const double end = scene.simulation.end_time;
        sim->run_until(end, [&](const sph::Simulation& s) {
            recorder->after_step(s);
            const auto now = std::chrono::steady_clock::now();
            const double since = std::chrono::duration<double>(now - last_report).count();
            if (since < (tty ? 0.25 : 10.0)) return;
            last_report = now;
            const double wall = std::chrono::duration<double>(now - t0).count();
            const double eta = s.time() > 0 ? wall * (end - s.time()) / s.time() : 0.0;
            char line[256];
            std::snprintf(line, sizeof line, "t = %.4f / %.3g s  step %lld  dt = %.3e s  wall %s  ETA %s", s.time(),
                          end, static_cast<long long>(s.steps()), s.world().step.dt, format_seconds(wall).c_str(),
                          format_seconds(eta).c_str());
            if (tty)
                std::fprintf(stderr, "\r%s   ", line);
            else
                spdlog::info("{}", line);
        });
        if (tty) std::fprintf(stderr, "\n");
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const auto summary = recorder->finish(*sim, wall, nthreads);
        spdlog::info("done: {} steps to t = {:.4f} s in {:.2f} s wall, {:.3g} fluid-particle-steps/s, "
                     "{:.0f} bytes per fluid particle (columns, grids, lists), peak RSS {:.1f} MiB",
                     sim->steps(), sim->time(), wall, summary["fluid_particle_steps_per_s"].get<double>(),
                     summary["bytes_per_fluid_particle"].get<double>(),
                     summary["peak_memory_bytes"].get<double>() / (1024.0 * 1024.0));
        for (const auto& s : summary["systems"])
            spdlog::info("  {:<22} {:8.3f} s  {:5.1f} %", s["name"].get<std::string>(), s["seconds"].get<double>(),
                         100.0 * s["share"].get<double>());
        spdlog::info("outputs in {}", out.string());
        return 0;
    } catch (const sph::InputError& e) {
        std::fprintf(stderr, "sph-run: error: %s\n", e.what());
        return 2;
    } catch (const sph::SimulationError& e) {
        std::fprintf(stderr, "\nsph-run: simulation failed: %s\n", e.what());
        if (recorder && sim) {
            try {
                recorder->finish(*sim, 0.0, threads);
            } catch (...) {
            }
        }
        return 3;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sph-run: internal error: %s\n", e.what());
        return 4;
    }
}
