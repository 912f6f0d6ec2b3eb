#pragma once
/// @file simulation.hpp
/// @brief Owns a World and the flow graph of a method's systems, and advances time.
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "engine/graph/system.hpp"
#include "engine/run/state_ring.hpp"
#include "engine/graph/system_graph.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"

namespace sph {

/// @brief A method is a recipe of systems chosen from the scene: `setup` runs once after
/// sampling, `step` every step (both as flow graphs).
struct Recipe {
    std::vector<std::unique_ptr<System>> setup;
    std::vector<std::unique_ptr<System>> step;
    /// States kept for a rollback (0: none). A step system requests one through res::rollback
    /// (request_dt > 0); Simulation::step then restores the state saved `rollback_steps` steps
    /// back and hands the step to resume with back in res::rollback's resume_dt.
    std::size_t rollback_steps = 0;
};

/// @brief The step just taken, as the outputs report it (also when it was rolled back and the
/// clock no longer describes it).
struct StepRecord {
    std::int64_t step = 0;
    double t = 0, dt = 0, dt_stable = 0;
    bool rolled_back = false;
};

class Simulation {
public:
    /// @brief Samples the scene, registers the recipe's components, runs the setup graph.
    Simulation(const Scene& scene, Recipe recipe);

    /// @brief Advances one step. Throws SimulationError on a NaN, a particle outside the
    /// domain or a step below dt_min, naming the particle, the step and the system.
    /// Unless set_synchronise_observers(false), every fluid row is at the clock's time after it.
    void step();
    /// @brief Brings every fluid row to the clock's time where the recipe drifts sleeping rows
    /// lazily (binned stepping: He et al. Alg. 2 lines 19-21 for the rows no system read this
    /// step); a no-op otherwise or when nothing is behind. Idempotent: the rows' values are
    /// those an eager drift would have given, bit for bit.
    void synchronise();
    /// @brief true (the default): step() and run_until's `after_step` see every row at the
    /// clock's time. false: only what the step read is current, and the caller calls
    /// synchronise() before it reads the whole fluid (sph-run does at frames and probes).
    /// run_until synchronises when it returns either way.
    void set_synchronise_observers(bool on) { m_sync_observers = on; }
    /// @brief Steps until `end_time` (the scene's by default), calling `after_step` each step.
    /// Returns false when it stopped earlier because request_stop() was called. A scene's
    /// standing wave is given to the fluid when the clock reads its `at` (the run is split there).
    bool run_until(double end_time, const std::function<void(const Simulation&)>& after_step = {});
    /// @brief Makes run_until return after the step in progress (safe from another thread or
    /// a signal handler's flag check; the state stays consistent, ready to be written).
    void request_stop() { m_stop.store(true, std::memory_order_relaxed); }
    /// @brief The world was replaced from outside (restore_checkpoint): the rollback ring's states
    /// belong to the old one and are dropped. restore_checkpoint then refills it from the
    /// checkpoint's "ring/..." sections and calls history_restored(); a checkpoint written before
    /// 2026-12-07 has none, so a rollback in the first steps after it reaches back at most to it
    /// (a recipe's depth of 2: an uninterrupted run would go one step further), and the run logs
    /// a warning when that happens.
    void forget_history();
    /// @brief The ring holds the states the checkpoint's run held: a short rollback is the
    /// uninterrupted run's, with no warning.
    void history_restored() { m_restored_at = -1; }
    /// @brief The rollback ring (nullptr when the recipe keeps none).
    const StateRing* ring() const { return m_ring.get(); }
    StateRing* ring() { return m_ring.get(); }

    World& world() { return m_world; }
    const World& world() const { return m_world; }
    double time() const { return m_world.clock.t; }
    std::int64_t steps() const { return m_world.clock.step; }
    /// @brief The step last taken.
    const StepRecord& last() const { return m_last; }
    /// @brief Seconds the last step spent re-sorting the particle columns before its systems ran
    /// (0 when it did not sort): engine work outside the graph's nodes.
    double last_sort_seconds() const { return m_sort_seconds; }
    /// @brief Whether the last step began with a re-sort of the particle columns.
    bool last_step_sorted() const { return m_sorted; }
    const SystemGraph& graph() const { return *m_graph; }
    /// @brief Bytes held by particle columns, grids and neighbour lists.
    std::size_t particle_bytes() const;
    /// @brief particle_bytes() by part: "fluid.<column>", "boundary.<column>", the two grids
    /// and the two neighbour lists, in that order.
    std::vector<std::pair<std::string, std::size_t>> memory_parts() const;

private:
    std::atomic<bool> m_stop{false};
    bool m_wave_given = false;
    bool m_sync_observers = true;
    bool m_behind = false;
    double m_sort_seconds = 0;  ///< last_sort_seconds()
    bool m_sorted = false;      ///< last_step_sorted()  ///< some fluid row is behind the clock (World::synchronise pending)
    /// One step without the observers' synchronisation.
    void step_once();
    /// run_until without the standing wave's split.
    bool advance(double end_time, const std::function<void(const Simulation&)>& after_step);
    /// Sets the fluid's velocity to the scene's standing wave if the clock reads its `at`.
    void give_wave_if_due();
    void check_step();
    void spatial_sort();
    /// Whether the particle columns are re-sorted before this step (SimulationParams::sort_interval).
    bool sort_due() const;
    /// Scans the fluid columns system i writes, on the rows it declares (Access::rows), for
    /// non-finite values (NaN, inf) and positions outside the domain, and keeps the earliest
    /// system in recipe order that produced each this step.
    void trace_non_finite(std::size_t system);

    /// Serves a rollback request after the graph ran: restores the ring, keeps the record.
    void serve_rollback();
    /// The system that owns the step size (the last in recipe order that writes res::dt).
    std::string step_size_owner() const;

    World m_world;
    std::unique_ptr<SystemGraph> m_graph;
    StepRecord m_last;
    std::size_t m_rollback_steps = 0;
    std::unique_ptr<StateRing> m_ring;
    std::int64_t m_restored_at = -1;  ///< the step a checkpoint restored (forget_history), or -1
    /// A fault of the step: system (recipe index), particle (row), column.
    struct Fault {
        std::size_t system = SIZE_MAX;
        std::size_t particle = 0;
        std::string column;
        /// The position found outside the domain, as the system left it (a later system, such
        /// as a collision net, may move the particle before the step's end is checked).
        Vec3 position = Vec3::Zero();
    };
    std::mutex m_trace_mutex;
    Fault m_non_finite;  ///< the first non-finite value
    Fault m_outside;     ///< the first position outside the domain
};

}  // namespace sph
