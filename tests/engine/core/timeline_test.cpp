// The integer timeline of binned stepping (engine/core/timeline.hpp) against brute force: the
// quantum nests dt_max exactly and lies at or below dt_min, bin_for is the largest bin whose
// step fits, and the alignment helpers agree with a loop over multiples.
#include "engine/core/timeline.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace sph;

TEST(Timeline, QuantumNestsDtMaxAndLiesBelowDtMin) {
    const double ranges[][2] = {{1e-7, 5e-3}, {1e-9, 1e6}, {2e-4, 2.5e-4}, {1e-6, 1e-3}, {3e-5, 7e-3}};
    for (const auto& r : ranges) {
        const BinTimeline t = BinTimeline::for_range(r[0], r[1]);
        // dt_max = 2^max_bin q exactly (ldexp only changes the exponent).
        EXPECT_EQ(t.seconds(BinTimeline::length(t.max_bin)), r[1]);
        EXPECT_LE(t.quantum, r[0]) << r[0] << " " << r[1];
        EXPECT_LT(t.max_bin, BinTimeline::kMaxBin);  // the cap is never reached in range
        // ... and not needlessly fine: q > dt_min / 2.
        EXPECT_GT(2 * t.quantum, r[0]);
        // Whole multiples stay exact in double (the run's time in quanta, up to 2^53).
        EXPECT_EQ(t.seconds(3 * BinTimeline::length(t.max_bin)), 3 * r[1]);
    }
    // 5 ms over 1e-7 s: 16 halvings (2^16 = 65536 >= 50000), where a 1 ps tick allows nine.
    EXPECT_EQ(BinTimeline::for_range(1e-7, 5e-3).max_bin, 16);
}

TEST(Timeline, BinForIsTheLargestBinThatFits) {
    const BinTimeline t = BinTimeline::for_range(1e-7, 5e-3);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-8.0, -1.0);
    for (int n = 0; n < 20000; ++n) {
        const double dt = std::pow(10.0, u(rng));
        int expected = 0;  // brute force: the largest b with 2^b q <= dt, clamped to [0, max_bin]
        for (int b = 0; b <= t.max_bin; ++b)
            if (t.seconds(BinTimeline::length(b)) <= dt) expected = b;
        ASSERT_EQ(t.bin_for(dt), expected) << dt;
    }
    // Exactly on a bin's step, and one ulp below it.
    for (int b = 0; b <= t.max_bin; ++b) {
        const double s = t.seconds(BinTimeline::length(b));
        EXPECT_EQ(t.bin_for(s), b);
        if (b > 0) {
            EXPECT_EQ(t.bin_for(std::nextafter(s, 0.0)), b - 1);
        }
    }
    EXPECT_EQ(t.bin_for(0.0), 0);
    EXPECT_EQ(t.bin_for(1e9), t.max_bin);
}

TEST(Timeline, AlignmentAgreesWithMultiples) {
    for (std::uint64_t n = 0; n < 4096; ++n)
        for (int b = 0; b < 14; ++b) {
            const std::uint64_t step = std::uint64_t(1) << b;
            ASSERT_EQ(BinTimeline::aligned(n, b), n % step == 0);
            std::uint64_t next = n + 1;  // brute force: the first multiple after n
            while (next % step) ++next;
            ASSERT_EQ(BinTimeline::next_aligned(n, b), next);
            int largest = 0;
            for (int c = 0; c <= 12; ++c)
                if (n % (std::uint64_t(1) << c) == 0) largest = c;
            ASSERT_EQ(BinTimeline::largest_aligned_bin(n, 12), largest) << n;
        }
}

// Rebasing (a full synchronisation restarts the timeline): a bin at headroom x the shortest
// step, or the fixed ladder's bin when that is as close; q <= dt_min and the top bin's step
// <= dt_max either way; the engine tick of quantum 0 is the origin.
TEST(Timeline, RebasedPutsABinNearTheShortestStep) {
    const double dt_min = 1e-7, dt_max = 5e-3;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-6.5, std::log10(dt_max));
    for (int n = 0; n < 5000; ++n) {
        const double shortest = std::pow(10.0, u(rng));
        for (const double headroom : {0.8, 1.0}) {
            const BinTimeline t = BinTimeline::rebased(shortest, headroom, dt_min, dt_max, 12345);
            ASSERT_EQ(t.origin, 12345);
            ASSERT_LE(t.quantum, dt_min);
            ASSERT_LE(t.seconds(BinTimeline::length(t.max_bin)), dt_max * (1 + 1e-15));
            // The bin the shortest step falls in is within the headroom of it, never above it.
            const double bin = t.seconds(BinTimeline::length(t.bin_for(shortest)));
            ASSERT_LE(bin, shortest * (1 + 1e-15)) << shortest;
            ASSERT_GE(bin, headroom * shortest * (1 - 1e-15)) << shortest << " " << headroom;
        }
    }
    // A shortest step on the fixed ladder keeps the fixed ladder (dt_max itself a bin).
    const BinTimeline fixed = BinTimeline::rebased(dt_max / 8, 0.8, dt_min, dt_max, 0);
    EXPECT_EQ(fixed.quantum, BinTimeline::for_range(dt_min, dt_max).quantum);
}
