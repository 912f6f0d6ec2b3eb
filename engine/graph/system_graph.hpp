#pragma once
/// @file system_graph.hpp
/// @brief Builds a tbb::flow::graph of continue_nodes from the systems' declared accesses,
/// once per run, and runs it every step. Each node is timed.
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "engine/graph/system.hpp"

namespace sph {
class Context;
}

namespace sph {

/// @brief A directed edge between systems, by their position in the recipe.
using Edge = std::pair<std::size_t, std::size_t>;

/// @brief Derives the dependency edges from declared accesses, in recipe order:
/// read-after-write (last writer -> reader), write-after-write (last writer -> writer) and
/// write-after-read (readers since the last write -> writer). Sorted, without duplicates.
/// A system that resizes a set (Access::resizes) conflicts with every access to that set.
std::vector<Edge> derive_edges(const std::vector<Access>& accesses);

class SystemGraph {
public:
    SystemGraph(std::vector<std::unique_ptr<System>> systems, World& world);
    ~SystemGraph();
    SystemGraph(const SystemGraph&) = delete;
    SystemGraph& operator=(const SystemGraph&) = delete;

    /// @brief Runs every system once, respecting the edges; independent systems run
    /// concurrently. Rethrows the first exception a system raised.
    void run();

    const std::vector<std::unique_ptr<System>>& systems() const { return m_systems; }
    const std::vector<Edge>& edges() const { return m_edges; }
    /// @brief The declaration of the i-th system, as the graph was built from it.
    const Access& access(std::size_t i) const { return m_accesses[i]; }
    /// @brief Seconds the i-th system took in the last run, and over all runs.
    double last_seconds(std::size_t i) const { return m_last[i]; }
    double total_seconds(std::size_t i) const { return m_total[i]; }
    /// @brief Called in the node right after system i ran (concurrently for independent
    /// systems), before its dependents start: the simulation checks the system's output
    /// there, so a NaN is traced to the system that produced it.
    void set_after_system(std::function<void(std::size_t)> fn) { m_after = std::move(fn); }
    /// @brief The graph in Graphviz dot form, nodes labelled with their accesses.
    std::string dot() const;

private:
    struct Impl;
    std::vector<std::unique_ptr<System>> m_systems;
    std::vector<Access> m_accesses;
    std::vector<std::unique_ptr<Context>> m_contexts;  ///< one per system, made from its Access
    std::vector<Edge> m_edges;
    std::vector<double> m_last, m_total;
    std::function<void(std::size_t)> m_after;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sph
