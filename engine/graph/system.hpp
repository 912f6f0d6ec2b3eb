#pragma once
/// @file system.hpp
/// @brief A system is one algorithm phase: a unique name, the data it reads and writes (an
/// Access of typed handles), and run(Context&). The graph builder derives the flow-graph
/// edges from the declarations; the Context hands the system only what it declared.
#include <cstdint>
#include <map>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "engine/core/access.hpp"

namespace sph {

struct World;
class Context;

/// @brief What a finished run adds up to, for System::summarise.
struct RunTotals {
    std::uint64_t kept_steps = 0;  ///< steps not discarded by a rollback
    /// Sum over kept steps of each counter, by name.
    const std::map<std::string, double, std::less<>>* counter_sums = nullptr;
    /// Sum over kept steps of each counter divided by the fluid count of that step.
    const std::map<std::string, double, std::less<>>* counter_per_fluid_sums = nullptr;
    double counter_sum(std::string_view name) const { return lookup(counter_sums, name); }
    double counter_per_fluid_sum(std::string_view name) const { return lookup(counter_per_fluid_sums, name); }

private:
    static double lookup(const std::map<std::string, double, std::less<>>* m, std::string_view name) {
        if (!m) return 0.0;
        const auto it = m->find(name);
        return it == m->end() ? 0.0 : it->second;
    }
};

class System {
public:
    virtual ~System() = default;
    /// @brief Unique, snake_case name; it names the graph node, its timing column
    /// (stats.csv `ms_<name>`) and diagnostics.
    virtual std::string name() const = 0;
    virtual Access access() const = 0;
    /// @brief Registers the columns and resources this system needs (once, after sampling and
    /// before any system runs; the only time a system sees the whole World).
    virtual void register_components(World& world) {}
    /// @brief One execution of the phase. Parallel inside; touches only what access() declares.
    virtual void run(Context& ctx) = 0;
    /// @brief Adds this system's part to summary.json at the end of a run (read-only).
    virtual void summarise(const World& world, const RunTotals& totals, nlohmann::json& summary) const {}
};

/// @brief Runs one system outside a graph, with a context made from its declaration (tests,
/// benchmarks and tools that drive systems by hand).
void run_system(System& system, World& world);
inline void run_system(System&& system, World& world) { run_system(system, world); }

}  // namespace sph
