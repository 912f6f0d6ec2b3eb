// sph-run: runs one scene and writes stats.csv, summary.json and frames.
// Exit codes: 0 ok, 2 bad input, 3 simulation failed, 4 internal error (a bug), 5 an output could
// not be written,
// 128 + signal when stopped by SIGINT/SIGTERM (after writing the summary).
#include <signal.h>
#include <csignal>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <cstdio>
#include <iostream>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "engine/run/checkpoint.hpp"
#include "engine/core/errors.hpp"
#include "engine/run/io.hpp"
#include "engine/run/recorder.hpp"
#include "engine/run/run_folder.hpp"
#include "systems/debug/nan_injection_system.hpp"
#include "systems/methods/recipes.hpp"

namespace {

/// The first SIGINT/SIGTERM: the run stops at the end of the step in progress and writes its
/// summary (and a checkpoint when checkpointing). The handler resets both signals to their
/// default action, so a second signal (either) stops the program at once.
std::atomic<int> g_stop_signal{0};  // lock-free: safe in a handler
static_assert(std::atomic<int>::is_always_lock_free);
extern "C" void on_stop_signal(int sig) {
    struct sigaction dfl {};  // sigaction and raise are async-signal-safe
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    int none = 0;
    if (!g_stop_signal.compare_exchange_strong(none, sig)) {
        // A second signal (perhaps handled at the same moment on another thread): stop at once.
        sigaction(sig, &dfl, nullptr);
        raise(sig);  // delivered when this handler returns, with the default action
        return;
    }
    sigaction(SIGINT, &dfl, nullptr);
    sigaction(SIGTERM, &dfl, nullptr);
}
void install_stop_handlers() {
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);  // the other stop signal waits until the handler has reset both
    sigaddset(&sa.sa_mask, SIGINT);
    sigaddset(&sa.sa_mask, SIGTERM);
    sa.sa_flags = 0;
    for (const int sig : {SIGINT, SIGTERM}) {
        struct sigaction old {};
        // A signal the parent ignores stays ignored (a background job of a script ignores SIGINT).
        if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        sigaction(sig, &sa, nullptr);
    }
}

constexpr const char* kHelpFooter = R"(
Outputs (in --out, default out/<scene name>):
  run.json                  the run that owns the folder (id, scene, pid); .sph-run.lock while it runs
  scene_as_run.json         the scene as run, every override applied (sph-run DIR/scene_as_run.json --out NEW runs it again)
  stats.csv                 one row per step; summary.json at the end (also when stopped early)
  frames/frame_NNNNN.EXT    particle frames, EXT per output.format (vtu, bgeo, ply); --no-frames for none
  surface/surface_NNNNN.EXT the fluid surface: .vdb level set (format vdb), .ply mesh (format mesh)
  boundary/                 walls.EXT once, moving_NNNNN.EXT per frame; frames.pvd for ParaView
  probes/<name>.csv         the scene's probes; checkpoints/ with --checkpoint-every
  A fresh run replaces the outputs of an earlier run in its folder; outputs no run.json claims
  are replaced only with --force.
Exit codes:
  0 done   2 bad input (scene, option, checkpoint, folder)   3 the simulation failed
  4 internal error (a bug in sph-run: please report the message)
  5 an output could not be written (disk full, read-only, path too long)
  130 / 143 stopped by SIGINT / SIGTERM after the step in progress (summary.json says "interrupted";
  a second signal stops at once)
)";

std::string format_seconds(double s) {
    char buf[32];
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%.1fs", s);
    else
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    return buf;
}

/// Refuses a scene that would not fit in this machine's physical memory, before anything is
/// sampled (the estimate: sph::estimate_size). The scene loader does not know the machine.
void check_memory(const sph::Scene& scene, const std::string& file,
                  const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
    const sph::SizeEstimate est = sph::estimate_size(scene);
    const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    if (!(physical > 0 && est.bytes > physical)) return;
    const auto large = [](double x, int decimals) {  // as the scene loader prints large numbers
        if (!std::isfinite(x)) return std::string("more than 1e308");
        char buf[64];
        if (x < 1e15)
            std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
        else
            std::snprintf(buf, sizeof buf, "%.3g", x);
        return std::string(buf);
    };
    if (est.boundary_bytes > 0.5 * est.bytes && !scene.boundaries.empty()) {
        // The boundary's sampling, not the fluid's, is what does not fit: name that boundary.
        const std::string path = "/boundaries/" + std::to_string(est.largest_boundary);
        throw sph::SceneError(file, path, "a boundary of about " + large(est.largest_boundary_particles, 0) +
                                              " boundary particles at this radius",
                              "a boundary that fits in memory: the boundaries would need about " +
                                  large(est.boundary_bytes / (1024.0 * 1024.0 * 1024.0), 1) +
                                  " GiB, more than this machine's physical memory (is a size or a position off "
                                  "by a unit?)");
    }
    std::string expected = "a larger radius: the scene would need about " +
                           large(est.bytes / (1024.0 * 1024.0 * 1024.0), 1) + " GiB for " +
                           large(est.fluid_particles, 0) + " fluid particles, more than this machine's physical memory";
    for (const auto& [path, value] : overrides)
        if (path == "/fluid/particle_radius" || path == "/simulation/scale") {
            expected += " (set on the command line)";
            break;
        }
    throw sph::SceneError(file, "/fluid/particle_radius", nlohmann::json(scene.fluid.particle_radius).dump(), expected);
}

/// A scene value a command-line option replaces must still be valid in the file itself
/// (`"end_time": "abc"` with `--end 1` is a broken scene that would fail the next run without
/// the option): the file is read once more without the overrides, and an error at an overridden
/// path (or below it) is reported; errors elsewhere belong to a scene meant to be completed on
/// the command line (a method's sections the override leaves unread, say) and are not.
void check_replaced_values(const std::string& text, const std::string& file,
                           const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
    if (overrides.empty()) return;
    try {
        sph::parse_scene(text, file);
    } catch (const sph::SceneError& e) {
        for (const auto& [path, value] : overrides) {
            const std::string& at = e.json_path();
            if (at == path || (at.size() > path.size() && at.compare(0, path.size(), path) == 0 && at[path.size()] == '/'))
                throw sph::InputError(std::string(e.what()) + " (in the scene file; the command line replaces it, but "
                                                              "the file's own value must be valid too)");
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"sph-run: simulate one SPH scene and write its outputs"};
    app.set_version_flag("--version", std::string("sph-run ") + SPH_VERSION);
    std::string scene_file, method, mode, out_dir, graph_file;
    double end_time = -1, dt = -1, scale = -1;
    int threads = 0;
    std::vector<std::string> sets;
    bool quiet = false, no_frames = false, list_modes = false;
    std::string inject_nan, resume_file, formats;
    double checkpoint_every = 0, frame_rate = -1;
    bool force = false;
    app.add_option("scene", scene_file, "Scene file (JSON); not with --resume");
    app.add_option("--method", method,
                   "Method: wcsph | pcisph | dfsph (the scene's mode is replaced by the method's default when it "
                   "belongs to another method)");
    app.add_option("--mode", mode,
                   "Stepping mode: constant | global | individual | binned (wcsph); constant | adaptive (pcisph, dfsph)");
    app.add_option("--end", end_time, "Simulated end time in seconds (overrides simulation.end_time)");
    app.add_option("--dt", dt, "Time step in seconds (constant mode only)");
    app.add_option("--scale", scale, "Particle-count multiplier (overrides simulation.scale)");
    app.add_option("--out", out_dir, "Output directory (default out/<scene name>)");
    app.add_option("--threads", threads, "Worker threads (default: all cores)");
    app.add_option("--graph", graph_file, "Write the system graph as Graphviz dot to this file");
    app.add_option("--set", sets, "Override a scene value: --set simulation.stepping.lambda_v=0.1 (one per --set; repeatable)")
        ->allow_extra_args(false);
    auto* no_frames_flag = app.add_flag("--no-frames", no_frames, "Write no particle frames");
    app.add_option("--frame-rate", frame_rate, "Frames per simulated second (overrides simulation.frame_rate; 0: none)")
        ->excludes(no_frames_flag);
    app.add_option("--format", formats, "Frame formats, comma-separated: vtu,bgeo,ply (particles), vdb,mesh (surface) (overrides output.format)");
    app.add_flag("--force", force, "Replace outputs in --out that no sph-run run claims (or another run's, resuming)");
    app.footer(kHelpFooter);
    app.add_option("--checkpoint-every", checkpoint_every,
                   "Write a checkpoint every T simulated seconds to <out>/checkpoints/checkpoint_NNNNNN.sphckpt");
    app.add_option("--resume", resume_file,
                   "Continue the run saved in this checkpoint (its scene and settings; --out, --threads, "
                   "--checkpoint-every, --graph, -q may be given)");
    app.add_option("--inject-nan", inject_nan,
                   "Testing aid: STEP:ID puts a NaN into particle ID's acceleration in step STEP, to exercise the "
                   "failure diagnosis (exit 3)");
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

    std::unique_ptr<sph::RunFolder> folder;  // declared first: released last
    std::unique_ptr<sph::Simulation> sim;
    std::unique_ptr<sph::Recorder> recorder;
    std::optional<std::chrono::steady_clock::time_point> run_started;  // for the summary of a salvaged run
    int run_threads = threads;  // the run's thread count once known (summaries of failed runs)
    const auto wall_so_far = [&] {
        return run_started ? std::chrono::duration<double>(std::chrono::steady_clock::now() - *run_started).count() : 0.0;
    };
    // What was computed is saved into the room the recorder kept in reserve (Recorder::salvage).
    const auto salvage = [&](const std::string& reason) {
        if (!recorder || !sim) return;
        for (const auto& line : recorder->salvage(*sim, reason, wall_so_far(), run_threads))
            std::fprintf(stderr, "sph-run: saved before stopping: %s\n", line.c_str());
    };
    try {
        std::vector<std::pair<std::string, nlohmann::json>> overrides;
        for (const auto& s : sets) overrides.push_back(sph::parse_override(s));
        if (!method.empty()) overrides.emplace_back("/simulation/method", method);
        if (!mode.empty()) overrides.emplace_back("/simulation/stepping/mode", mode);
        if (end_time >= 0 || app.count("--end")) overrides.emplace_back("/simulation/end_time", end_time);
        if (dt >= 0 || app.count("--dt")) overrides.emplace_back("/simulation/stepping/dt", dt);
        if (scale >= 0 || app.count("--scale")) overrides.emplace_back("/simulation/scale", scale);
        if (app.count("--frame-rate")) overrides.emplace_back("/simulation/frame_rate", frame_rate);
        if (no_frames) overrides.emplace_back("/simulation/frame_rate", 0.0);
        if (app.count("--format")) {
            nlohmann::json list = nlohmann::json::array();
            std::size_t start = 0;
            while (start <= formats.size()) {
                const std::size_t comma = std::min(formats.find(',', start), formats.size());
                list.push_back(formats.substr(start, comma - start));
                start = comma + 1;
            }
            overrides.emplace_back("/output/format", list);
        }
        if (threads < 0) throw sph::InputError("--threads: found " + std::to_string(threads) + ", expected a count >= 0");
        if (app.count("--checkpoint-every") && !(checkpoint_every > 0 && std::isfinite(checkpoint_every)))
            throw sph::InputError("--checkpoint-every: found " + std::to_string(checkpoint_every) +
                                  ", expected a time > 0 (simulated seconds)");

        // The scene: from the file and the command line, or (resuming) from the checkpoint,
        // which keeps the scene's text and overrides so the run continues exactly as it began.
        std::optional<sph::Checkpoint> checkpoint;
        std::string scene_text;
        if (!resume_file.empty()) {
            if (!scene_file.empty() || !overrides.empty())
                throw sph::InputError("--resume: found a scene file or scene options, expected none (a resumed run "
                                      "continues with the checkpoint's scene and settings)");
            checkpoint = sph::read_checkpoint(resume_file);
            sph::check_run_meta(*checkpoint);
            const auto& m = checkpoint->meta;
            scene_file = m["scene_file"].get<std::string>();
            scene_text = m["scene_text"].get<std::string>();
            for (const auto& o : m["overrides"]) overrides.emplace_back(o[0].get<std::string>(), o[1]);
            if (out_dir.empty()) out_dir = m["out"].get<std::string>();
            if (!app.count("--checkpoint-every")) checkpoint_every = m.value("checkpoint_every", 0.0);
            spdlog::info("resuming {} at step {}, t = {} s", resume_file, m["step"].get<long long>(),
                         m["t"].get<double>());
        } else {
            if (scene_file.empty()) throw sph::InputError("a scene file is required (or --resume CHECKPOINT)");
            scene_text = sph::read_scene_file(scene_file);
        }
        for (const auto& [path, value] : overrides)
            spdlog::info("command line sets {} = {}", path, value.dump());

        if (list_modes) {  // every pair the loader accepts for this scene (tools/sph_study.py)
            sph::parse_scene(scene_text, scene_file, overrides);  // the scene itself must load
            for (const auto& method : sph::method_names())
                for (const auto& m : sph::stepping_mode_names()) {
                    auto o = overrides;
                    o.emplace_back("/simulation/method", method);
                    o.emplace_back("/simulation/stepping/mode", m);
                    try {
                        sph::parse_scene(scene_text, scene_file, o);
                        std::printf("%s %s\n", method.c_str(), m.c_str());
                    } catch (const sph::SceneError&) {
                    }
                }
            return 0;
        }
        sph::Scene scene = sph::parse_scene(scene_text, scene_file, overrides);
        check_replaced_values(scene_text, scene_file, overrides);
        scene.source = scene_file;
        check_memory(scene, scene_file, overrides);
        // The output folder is claimed before the (possibly long) set-up: a folder in use, a file
        // in its place or a path the file system refuses stops the run before any sampling.
        const std::filesystem::path out =
            out_dir.empty() ? std::filesystem::path("out") / scene.name : std::filesystem::path(out_dir);
        const std::string run_id =
            checkpoint ? checkpoint->meta.value("run_id", std::string()) : sph::new_run_id();
        folder = std::make_unique<sph::RunFolder>(out, run_id, scene.name, checkpoint.has_value(), force);
        // oneTBB's arena runs at most the machine's concurrency, whatever the limit says.
        const int cores = tbb::info::default_concurrency();
        if (threads > cores)
            spdlog::warn("--threads {}: this machine runs {} thread(s) at once; the run uses {}", threads, cores, cores);
        const int nthreads = threads > 0 ? std::min(threads, cores) : cores;
        run_threads = nthreads;
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(nthreads));

        const auto t_setup = std::chrono::steady_clock::now();
        sph::Recipe recipe = sph::make_recipe(scene);
        if (!inject_nan.empty()) {
            long long step = -1, id = -1;
            char tail = 0;
            if (std::sscanf(inject_nan.c_str(), "%lld:%lld%c", &step, &id, &tail) != 2 || step < 0 || id < 0 ||
                id > 0xffffffffLL)
                throw sph::InputError("--inject-nan: found \"" + inject_nan +
                                      "\", expected STEP:ID with a step index >= 0 and a particle id >= 0");
            sph::add_nan_injection(recipe, step, std::uint32_t(id));
        }
        sim = std::make_unique<sph::Simulation>(scene, std::move(recipe));
        if (checkpoint) sph::restore_checkpoint(*sim, *checkpoint);
        const auto& w = sim->world();
        spdlog::info("scene '{}' from {}: {} fluid + {} boundary particles, r = {} m, h = {} m, c_s = {:.3g} m/s, "
                     "mass = {:.4g} kg, method {} / {}, end {} s, {} thread(s), set-up {:.2f} s",
                     scene.name, scene_file, w.fluid.size(), w.boundary.size(), w.physics.particle_radius,
                     w.physics.h, w.physics.speed_of_sound, w.physics.mass, sph::to_string(scene.simulation.method),
                     sph::to_string(scene.simulation.stepping.mode), scene.simulation.end_time, nthreads,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t_setup).count());
        if (!graph_file.empty()) {
            sph::write_file_atomic(graph_file, sim->graph().dot());
            spdlog::info("system graph written to {}", graph_file);
        }
        // A resume into a folder whose stats.csv is another run's is refused before the folder is
        // taken, so that nothing in it changes (with --force the folder's outputs are replaced).
        // The checkpoint's recorder state read by `use`; a state without the keys sph-run writes
        // names the checkpoint.
        const auto with_recorder_state = [&](const auto& use) {
            try {
                use(checkpoint->meta.at("recorder"));
            } catch (const nlohmann::json::exception& e) {
                throw sph::CheckpointError(resume_file + ": meta key 'recorder' is not what sph-run writes (" +
                                           e.what() + ")");
            }
        };
        if (checkpoint && !folder->replaces())
            with_recorder_state([&](const nlohmann::json& st) { sph::Recorder::check_resume(out, *sim, st); });
        // Set-up succeeded: only now are an earlier run's outputs replaced (a run that fails
        // before this point leaves them as they were).
        folder->take();
        if (!folder->note().empty()) spdlog::info("{}", folder->note());
        if (checkpoint) {
            with_recorder_state(
                [&](const nlohmann::json& st) { recorder = std::make_unique<sph::Recorder>(out, *sim, st); });
        } else {
            recorder = std::make_unique<sph::Recorder>(out, *sim);
            recorder->begin(*sim);
        }
        folder->keep();
        // Checkpoints at multiples of T simulated seconds (after the step that reaches one).
        nlohmann::json overrides_json = nlohmann::json::array();
        for (const auto& [path, value] : overrides) overrides_json.push_back({path, value});
        double next_checkpoint =
            checkpoint_every > 0 ? (std::floor(sim->time() / checkpoint_every + 1e-9) + 1) * checkpoint_every : 0.0;
        auto write_checkpoint = [&](const sph::Simulation& s) {
            // Absolute paths: a resume from another working directory finds the run's folder and
            // the files the scene names relative to itself (meshes).
            std::error_code ec;
            const auto absolute = [&](const std::filesystem::path& p) {
                const auto a = std::filesystem::absolute(p, ec);
                return (ec ? p : a).lexically_normal().string();
            };
            nlohmann::json meta = {{"scene_file", absolute(scene_file)},
                                   {"scene_text", scene_text},
                                   {"overrides", overrides_json},
                                   {"out", absolute(out)},
                                   {"run_id", folder->run_id()},
                                   {"checkpoint_every", checkpoint_every},
                                   {"step", s.steps()},
                                   {"t", s.time()},
                                   {"sph_version", SPH_VERSION}};
            meta["recorder"] = recorder->state();
            char name[48];
            std::snprintf(name, sizeof name, "checkpoint_%06lld.sphckpt", static_cast<long long>(s.steps()));
            sph::write_checkpoint(out / "checkpoints" / name, s, meta);
            return out / "checkpoints" / name;
        };

        const bool tty = ::isatty(STDERR_FILENO);
        const auto t0 = std::chrono::steady_clock::now();
        run_started = t0;
        auto last_report = t0;
        const double end = scene.simulation.end_time;
        install_stop_handlers();
        // Binned stepping drifts sleeping rows lazily: the whole fluid is brought to the clock's
        // time only when an output reads it (frames, probes, fronts, checkpoints).
        sim->set_synchronise_observers(false);
        const bool reached_end = sim->run_until(end, [&](const sph::Simulation& s) {
            if (recorder->reads_particles(s)) sim->synchronise();
            recorder->after_step(s);
            if (g_stop_signal.load()) {
                sim->request_stop();
                return;
            }
            if (checkpoint_every > 0 && s.time() >= next_checkpoint - 1e-9 && s.time() < end - 1e-9) {
                sim->synchronise();
                write_checkpoint(s);
                next_checkpoint = (std::floor(s.time() / checkpoint_every + 1e-9) + 1) * checkpoint_every;
            }
            const auto now = std::chrono::steady_clock::now();
            const double since = std::chrono::duration<double>(now - last_report).count();
            if (since < (tty ? 0.25 : 10.0)) return;
            last_report = now;
            const double wall = std::chrono::duration<double>(now - t0).count();
            const double eta = s.time() > 0 ? wall * (end - s.time()) / s.time() : 0.0;
            char line[256];
            std::snprintf(line, sizeof line, "t = %.4f / %.3g s  step %lld  dt = %.3e s  wall %s  ETA %s", s.time(),
                          end, static_cast<long long>(s.steps()), s.world().step_size.dt, format_seconds(wall).c_str(),
                          format_seconds(eta).c_str());
            if (tty)
                std::fprintf(stderr, "\r%s   ", line);
            else
                spdlog::info("{}", line);
        });
        if (tty) std::fprintf(stderr, "\n");
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const int stop_signal = reached_end ? 0 : g_stop_signal.load();
        std::string resume_hint;
        if (stop_signal) {
            const char* name = stop_signal == SIGINT ? "SIGINT" : stop_signal == SIGTERM ? "SIGTERM" : "a signal";
            recorder->set_interrupted(name);
            if (checkpoint_every > 0) resume_hint = "; continue with: sph-run --resume " + write_checkpoint(*sim).string();
        }
        const auto summary = recorder->finish(*sim, wall, nthreads);
        if (stop_signal) {
            std::fprintf(stderr, "sph-run: stopped by %s at t = %.6g s (step %lld of the run to %g s); summary.json "
                                 "is marked \"interrupted\"%s\n",
                         stop_signal == SIGINT ? "SIGINT" : "SIGTERM", sim->time(), static_cast<long long>(sim->steps()),
                         end, resume_hint.c_str());
            return 128 + stop_signal;
        }
        spdlog::info("done: {} steps to t = {:.4f} s in {:.2f} s wall, {:.3g} fluid-particle-steps/s, "
                     "{:.0f} bytes per fluid particle (columns, grids, lists), peak RSS {:.1f} MiB",
                     sim->steps(), sim->time(), wall, summary["fluid_particle_steps_per_s"].get<double>(),
                     summary["bytes_per_fluid_particle"].get<double>(),
                     summary["peak_memory_bytes"].get<double>() / (1024.0 * 1024.0));
        for (const auto& s : summary["systems"])
            spdlog::info("  {:<22} {:8.3f} s  {:5.1f} %", s["name"].get<std::string>(), s["seconds"].get<double>(),
                         100.0 * s["share"].get<double>());
        std::string fmts;
        for (const auto f : scene.output.formats) fmts += std::string(fmts.empty() ? "" : ", ") + sph::to_string(f);
        std::string where = scene.output.writes_particles() ? (out / "frames").string() : "";
        if (scene.output.writes_surface()) where += (where.empty() ? "" : " and ") + (out / "surface").string();
        spdlog::info("wrote {} frame(s) ({}) to {}, stats.csv and summary.json to {}", recorder->frames_written(),
                     recorder->frames_written() ? fmts : "none", where, out.string());
        if (const auto it = summary.find("surface"); it != summary.end())
            spdlog::info("surfaces: {:.3f} s per frame, {:.1f} steps' worth", (*it)["seconds_per_frame"].get<double>(),
                         (*it)["steps_per_frame"].get<double>());
        return 0;
    } catch (const sph::InputError& e) {
        std::fprintf(stderr, "sph-run: error: %s\n", e.what());
        return 2;
    } catch (const sph::SimulationError& e) {
        std::fprintf(stderr, "\nsph-run: simulation failed: %s\n", e.what());
        if (recorder && sim) {
            recorder->set_failed(e.what());
            try {
                recorder->finish(*sim, wall_so_far(), run_threads);
                std::fprintf(stderr, "sph-run: stats.csv, probes and summary.json (marked \"failed\") cover the run "
                                     "to its last good step\n");
            } catch (const std::exception& w) {  // no room left (or a folder gone): the reserve's turn
                std::fprintf(stderr, "sph-run: cannot write an output: %s\n", w.what());
                salvage(w.what());
            }
        }
        return 3;
    } catch (const sph::OutputError& e) {
        std::fprintf(stderr, "\nsph-run: cannot write an output: %s\n", e.what());
        salvage(e.what());
        return 5;
    } catch (const std::filesystem::filesystem_error& e) {  // e.g. out of inodes creating a folder
        std::fprintf(stderr, "\nsph-run: cannot write an output: %s\n", e.what());
        salvage(e.what());
        return 5;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sph-run: internal error: %s\n", e.what());
        return 4;
    }
}
