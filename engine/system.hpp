#pragma once
/// @file system.hpp
/// @brief A system is one algorithm phase: a name, the resources it reads and writes, and
/// run(). The graph builder derives the flow-graph edges from those declarations.
#include <string>
#include <vector>

namespace sph {

struct World;

/// @brief Resource names are "<set>.<component>" for particle columns ("fluid.density") and
/// plain names for everything else ("fluid.neighbours", "step.dt").
struct Access {
    std::vector<std::string> reads;
    std::vector<std::string> writes;
};

class System {
public:
    virtual ~System() = default;
    /// @brief Unique, snake_case name; it names the graph node, the timing and diagnostics.
    virtual std::string name() const = 0;
    virtual Access access() const = 0;
    /// @brief Registers the columns this system needs (called once, after sampling).
    virtual void register_components(World& world) {}
    /// @brief One execution of the phase. Parallel inside; never touches undeclared data.
    virtual void run(World& world) = 0;
};

}  // namespace sph
