#pragma once
/// @file emitter_system.hpp
/// @brief Inserts fluid particles from the scene's emitters at the start of a step (before the
/// grid and the neighbour search). Never inside another particle or a boundary: a candidate
/// closer than 0.95 r0 to any fluid or boundary particle waits for a later step.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief The emitters' progress (one entry per scene emitter), a Kept resource: rollbacks and
/// checkpoints copy it.
struct EmitterState {
    std::vector<double> budget;          ///< particles owed (rate x elapsed time - emitted)
    std::vector<std::uint64_t> emitted;  ///< particles inserted so far
    std::uint32_t next_id = 0;           ///< id of the next inserted particle
    void save(std::string& out) const;
    /// @brief Throws std::runtime_error when the bytes do not hold a state of this size.
    void load(std::string_view in);
};

namespace res {
inline constexpr Resource<EmitterState> emitter_state{"emitters.state"};
}  // namespace res

class EmitterSystem final : public System {
public:
    /// @param scale the scene's particle-count multiplier (rates and totals are per scale 1).
    EmitterSystem(std::vector<EmitterDesc> emitters, double scale) : m_emitters(std::move(emitters)), m_scale(scale) {}
    std::string name() const override { return "emitters"; }
    Access access() const override;
    /// @brief Creates the state: nothing owed or emitted, ids continuing after the sampled fluid.
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    std::vector<EmitterDesc> m_emitters;
    double m_scale;
};

}  // namespace sph
