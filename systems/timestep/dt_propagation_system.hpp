#pragma once
/// @file dt_propagation_system.hpp
/// @brief Individual time stepping, He et al. Alg. 2 line 16 (Delta t_i = min over the
/// neighbours j of Delta t_j^raw, i itself included) over the active particles and their halo;
/// line 17 is individual_dt_system.hpp.
#include <tbb/enumerable_thread_specific.h>

#include <vector>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief He Alg. 2 line 16, run only where a Delta t^raw changed: for every active particle
/// and every inactive neighbour of one (the halo, He sec. 2.3's observation before Alg. 2, which it also
/// collects, ascending, into fluid.halo_set). Each gets the minimum over its own list (fresh
/// for the active, the last one for the halo) and itself; a halo particle also gets the
/// Delta t^raw of every active particle whose fresh list holds it, so a sleeping particle that
/// an active one has just come near learns the short step at once.
class DtPropagationSystem final : public System {
public:
    std::string name() const override { return "dt_propagation"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    /// Per worker, the smallest Delta t^raw of an active particle reaching each particle
    /// (+infinity between runs).
    tbb::enumerable_thread_specific<std::vector<double>> m_reach;
};

}  // namespace sph
