#pragma once
/// @file halo_system.hpp
/// @brief Individual time stepping: the inactive neighbours of active particles (the halo).
#include <cstdint>
#include <vector>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Inactive fluid neighbours of active particles (He Alg. 2, remark after line 22:
/// lines 9 and 16 are needed only there), from the active particles' fresh lists; also
/// counts the boundary contributions of the active particles.
class HaloSystem final : public System {
public:
    explicit HaloSystem(bool with_boundary) : m_with_boundary(with_boundary) {}
    std::string name() const override { return "halo"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_with_boundary;
    std::vector<std::uint8_t> m_claim;
};

}  // namespace sph
