#pragma once
/// @file pcisph_state.hpp
/// @brief PCISPH's state between steps and between passes (Ihmsen et al. 2010 Alg. 2 and sec.
/// 3.3), as resources the PCISPH systems own. The Kept ones are copied by rollbacks and
/// checkpoints generically (engine/core/resources.hpp).
#include <vector>

#include "engine/core/access.hpp"
#include "engine/core/types.hpp"

namespace sph {

/// @brief delta of eq. 4-5 and the step it was computed for (recomputed when dt changes).
struct PcisphDelta {
    double delta = 0;
    double delta_dt = 0;
};

/// @brief The last prediction-correction pass: max and mean of max(rho*/rho0 - 1, 0), and the
/// passes taken this step.
struct PcisphErrors {
    double pred_err_max = 0, pred_err_avg = 0;
    int iterations = 0;
};

/// @brief The adaptive controller's state (sec. 3.3).
struct PcisphController {
    double pending_dt = 0;     ///< the step the next step takes (0: the initial rule)
    double prev_err_max = -1;  ///< rho_err^max(t - dt) for eq. 25 (< 0: none yet)
    double v_max_tracked = 0, a_max_tracked = 0;  ///< over all kept steps: v^max, F^max of eq. 14-15
    double rho_err_avg_max = 0;                   ///< max over kept steps of rho_err^avg
    int reason = 0;  ///< the last decision (AdaptiveDecision)
};

/// @brief Boundary particles with at least one fluid neighbour (Ihmsen 2010 sec. 3.4: only
/// those are active) and their fluid neighbours, as compressed rows over the active set.
/// Rebuilt every step.
struct BoundaryActive {
    std::vector<Index> set;    ///< ascending boundary indices
    std::vector<Index> start;  ///< set.size() + 1 offsets into `fluid`
    std::vector<Index> fluid;  ///< fluid neighbours (r < h) of each active boundary particle
};

namespace res {
inline constexpr Resource<PcisphDelta> pcisph_delta{"pcisph.delta"};
inline constexpr Resource<PcisphErrors> pcisph_errors{"pcisph.errors"};
inline constexpr Resource<PcisphController> pcisph_controller{"pcisph.controller"};
inline constexpr Resource<BoundaryActive> boundary_active{"boundary.active_set"};  ///< + boundary->fluid lists
}  // namespace res

}  // namespace sph
