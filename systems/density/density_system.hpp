#pragma once
/// @file density_system.hpp
/// @brief He et al. eq. 1 (summation density) plus the boundary contribution of Akinci et al.
/// 2012 eq. 6, then the Tait pressure (He eq. 2). With individual stepping (He Alg. 2
/// lines 5-9) only active particles are summed, and the sum is kept as their base density;
/// the interpolation of line 9 happens in the asynchronous integration.
#include "engine/graph/system.hpp"

namespace sph {

class DensitySystem final : public System {
public:
    /// @param with_boundary add the boundary contribution (only when the scene has one).
    /// @param individual sum only the active set.
    explicit DensitySystem(bool with_boundary, bool individual = false)
        : m_with_boundary(with_boundary), m_individual(individual) {}
    std::string name() const override { return "density"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_with_boundary, m_individual;
};

}  // namespace sph
