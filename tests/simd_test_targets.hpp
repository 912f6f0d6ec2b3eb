#pragma once
// Runs a test body once for each vectorised target the engine compiled that this CPU runs (on
// x86 AVX-512, AVX2 and the portable EMU128), forced through Highway's test mock: a machine with
// AVX-512 checks the AVX2 code too (each target has code of its own: AVX2's compress in the
// neighbour filter and its row loads in the pair loops are ours).
#include <gtest/gtest.h>

#include "engine/core/simd_targets.hpp"  // the targets the engine compiled, before Highway

#include <hwy/highway.h>
#include <hwy/targets.h>

#include <cstdint>
#include <vector>

namespace sph::test {

template <class F>
void for_each_simd_target(F&& fn) {
    const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
    ASSERT_FALSE(targets.empty());
    for (const std::int64_t target : targets) {
        SCOPED_TRACE(hwy::TargetName(target));
        hwy::SetSupportedTargetsForTest(target);
        hwy::GetChosenTarget().DeInit();  // the next dispatch chooses again, under the mock
        fn();
    }
    hwy::SetSupportedTargetsForTest(0);
    hwy::GetChosenTarget().DeInit();
}

}  // namespace sph::test
