#pragma once
/// @file nan_injection_system.hpp
/// @brief Fault injection for tests of the failure diagnosis (not a physics phase): at one
/// step it overwrites one particle's acceleration with NaN, as a broken force term would.
#include <cstdint>

#include "engine/run/simulation.hpp"
#include "engine/graph/system.hpp"

namespace sph {

class NanInjectionSystem final : public System {
public:
    /// @param step index of the step (0-based) in which to inject
    /// @param particle_id stable id (comp::id) of the particle that gets the NaN
    NanInjectionSystem(std::int64_t step, std::uint32_t particle_id) : m_step(step), m_id(particle_id) {}
    std::string name() const override { return "inject_nan"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    std::int64_t m_step;
    std::uint32_t m_id;
};

/// @brief Inserts a NanInjectionSystem right after the recipe's `forces` system (at the end
/// when there is none).
void add_nan_injection(Recipe& recipe, std::int64_t step, std::uint32_t particle_id);

}  // namespace sph
