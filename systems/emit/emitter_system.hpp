#pragma once
/// @file emitter_system.hpp
/// @brief Inserts fluid particles from the scene's emitters at the start of a step (before the
/// grid and the neighbour search). Never inside another particle or a boundary: a candidate
/// closer than 0.95 r0 to any fluid or boundary particle waits for a later step.
#include "engine/system.hpp"

namespace sph {

class EmitterSystem final : public System {
public:
    std::string name() const override { return "emitters"; }
    Access access() const override;
    void run(World& w) override;
};

}  // namespace sph
