#pragma once
/// @file binned_select_system.hpp
/// @brief Binned stepping, the start of a step: when the clock has reached the planned due
/// time (BinTimeline::next), the active set is that time's bucket (particles with ti_end ==
/// now); BinnedBodySystem adds the particles within reach of a moving body once the step's grid
/// is known. A step that ends at a frame or the run's end between two due times has no active
/// particle. Cost: O(active) per step (the bucket and the previous step's flags); O(N) only when
/// the fluid rows were reordered, added or restored (the buckets are rebuilt from ti_end).
#include "engine/graph/system.hpp"

namespace sph {

class BinnedSelectSystem final : public System {
public:
    /// @param dt_min, dt_max the scene's step range (they fix the timeline's quantum).
    BinnedSelectSystem(double dt_min, double dt_max) : m_dt_min(dt_min), m_dt_max(dt_max) {}
    std::string name() const override { return "binned_select"; }
    Access access() const override;
    /// @brief Registers bin, ti_end, dt, t_last, active and the timeline (Kept) and buckets.
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    double m_dt_min, m_dt_max;
};

}  // namespace sph
