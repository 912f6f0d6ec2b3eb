// The vectorised per-particle step (systems/timestep/step_bound_simd.hpp) against StepBound, the
// scalar He et al. Alg. 2 line 13 that ForcesSystem's reference loop runs: bit for bit (the
// contract; a contracted multiply-add, a different sum order or a NaN let through the min
// changes the last bit or more), on every vectorised target this CPU runs, over rows that
// exercise each branch: every condition winning, zero speed and acceleration, denormal, huge,
// infinite and NaN inputs, index lists and contiguous ranges with tails of every length.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "simd_test_targets.hpp"
#include "systems/timestep/step_bound_simd.hpp"

using namespace sph;

namespace {

/// xyz rows: random magnitudes over 30 decades and the special values of the contract.
std::vector<Real> rows_of(std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(-1, 1), decade(-20, 10);
    std::vector<Real> x(3 * n);
    const Real special[] = {0, -0.0f, std::numeric_limits<Real>::denorm_min(), std::numeric_limits<Real>::max(),
                            std::numeric_limits<Real>::infinity(), std::numeric_limits<Real>::quiet_NaN()};
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            const auto pick = rng() % 16;
            x[3 * i + c] = pick < 6 && i % 5 == 0 ? special[pick] : Real(unit(rng) * std::pow(10.0, decade(rng)));
        }
    for (int c = 0; c < 3; ++c) x[c] = 0;  // row 0 at rest
    return x;
}

double reference(const StepBound& b, const Real* v, const Real* a, std::size_t i) {
    return b.of(Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]), Vec3(a[3 * i], a[3 * i + 1], a[3 * i + 2]));
}

void expect_bitwise(const std::vector<double>& got, const std::vector<double>& want, const char* what) {
    std::size_t differ = 0, first = got.size();
    for (std::size_t i = 0; i < got.size(); ++i)
        if (std::bit_cast<std::uint64_t>(got[i]) != std::bit_cast<std::uint64_t>(want[i])) {
            ++differ;
            if (first == got.size()) first = i;
        }
    EXPECT_EQ(differ, 0u) << what << ": first at row " << first << ": " << got[first] << " against " << want[first];
}

}  // namespace

TEST(StepBoundSimd, EqualsStepBoundBitForBit) {
    constexpr std::size_t n = 1031;  // a prime: tails of every length below
    const std::vector<Real> v = rows_of(n, 1), a = rows_of(n, 2);
    // He's lambda with and without the acoustic condition, and a viscous cap (Morris et al. 1997).
    struct Case {
        bool acoustic;
        double nu;
    };
    for (const Case& c : {Case{true, 0}, Case{false, 0}, Case{true, 1e-2}}) {
        SteppingParams p;
        p.acoustic = c.acoustic;
        p.lambda_c = 1.0;
        const StepBound bound(p, 0.04, 39.6, c.nu);
        std::vector<double> want(n);
        for (std::size_t i = 0; i < n; ++i) want[i] = reference(bound, v.data(), a.data(), i);
        // Each condition must win somewhere, or the comparison would not cover it.
        std::size_t capped = 0, by_speed = 0, by_force = 0, acoustic = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 vi(v[3 * i], v[3 * i + 1], v[3 * i + 2]), ai(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
            const double sv = std::sqrt(double(vi.squaredNorm())), sa = std::sqrt(double(ai.squaredNorm()));
            if (want[i] == bound.cap) ++capped;
            if (sv > 0 && want[i] == bound.lambda_vh / sv) ++by_speed;
            if (sa > 0 && want[i] == bound.lambda_f * std::sqrt(bound.h / sa)) ++by_force;
            if (c.acoustic && want[i] == bound.lambda_ch / (bound.c_s + sv)) ++acoustic;
        }
        EXPECT_GT(capped, 0u);
        EXPECT_GT(by_speed, 0u);
        EXPECT_GT(by_force, 0u);
        if (c.acoustic) {
            EXPECT_GT(acoustic, 0u);
        }
        test::for_each_simd_target([&] {
            std::vector<double> got(n, -1);
            step_bounds_simd(bound, v.data(), a.data(), n, nullptr, 0, n, got.data());
            expect_bitwise(got, want, "contiguous rows");
            // A shuffled subset of the rows, in ranges that start and end anywhere.
            std::vector<Index> rows(n);
            std::iota(rows.begin(), rows.end(), Index(0));
            std::shuffle(rows.begin(), rows.end(), std::mt19937(3));
            rows.resize(n - 100);
            std::vector<double> sub(n, -1), sub_want(n, -1);
            for (std::size_t b = 0; b < rows.size();) {
                const std::size_t e = std::min(rows.size(), b + 1 + b % 37);
                step_bounds_simd(bound, v.data(), a.data(), n, rows.data(), b, e, sub.data());
                b = e;
            }
            for (Index i : rows) sub_want[i] = want[i];
            expect_bitwise(sub, sub_want, "listed rows (the others untouched)");
        });
    }
}
