#pragma once
/// @file select_active_system.hpp
/// @brief He et al. Alg. 2 line 2 (select active). Particle i is active at simulated time t
/// when t_last_i + Delta t_i <= t, compared in integer ticks (exact; the tie counts as
/// active), or when a system woke it (a wall contact since its last evaluation).
/// Delta t_i is converted to ticks rounding down, the same way the global step is, so the
/// particle that sets Delta t_sim is active exactly one step later.
#include <cstdint>
#include <vector>

#include "engine/system.hpp"

namespace sph {

class SelectActiveSystem final : public System {
public:
    std::string name() const override { return "select_active"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(World& w) override;
};

/// @brief Inactive fluid neighbours of active particles (He Alg. 2, remark after line 22:
/// lines 9 and 16 are needed only there), from the active particles' fresh lists; also
/// counts the boundary contributions of the active particles.
class HaloSystem final : public System {
public:
    explicit HaloSystem(bool with_boundary) : m_with_boundary(with_boundary) {}
    std::string name() const override { return "halo"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(World& w) override;

private:
    bool m_with_boundary;
    std::vector<std::uint8_t> m_claim;
};

}  // namespace sph
