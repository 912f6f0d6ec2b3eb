#pragma once
/// @file repeat_system.hpp
/// @brief A system that runs a sub-graph of systems k times per step, k decided after each pass
/// by a predicate (a solver's prediction-correction loop). The sub-graph is an ordinary
/// SystemGraph built from its systems' declared accesses; towards the outer graph the node
/// declares the union of their accesses plus what `extra` adds (what its predicates read and
/// write, such as an iteration counter).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/graph/system.hpp"
#include "engine/graph/system_graph.hpp"

namespace sph {

class RepeatSystem final : public System {
public:
    /// @param more called after pass k (k = 1, 2, ...) with this node's context: true runs another pass.
    /// @param done called once after the last pass with the number of passes.
    RepeatSystem(std::string name, std::vector<std::unique_ptr<System>> body,
                 std::function<bool(const Context&, int)> more, std::function<void(Context&, int)> done = {},
                 Access extra = {});
    std::string name() const override { return m_name; }
    Access access() const override { return m_access; }
    /// @brief Registers the body's components and builds its graph (once).
    void register_components(World& w) override;
    void run(Context& ctx) override;
    /// @brief The body's graph (built by register_components); null before.
    const SystemGraph* body() const { return m_graph.get(); }

private:
    std::string m_name;
    std::vector<std::unique_ptr<System>> m_body;
    std::function<bool(const Context&, int)> m_more;
    std::function<void(Context&, int)> m_done;
    Access m_access;
    std::unique_ptr<SystemGraph> m_graph;
};

}  // namespace sph
