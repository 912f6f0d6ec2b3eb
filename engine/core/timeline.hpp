#pragma once
/// @file timeline.hpp
/// @brief The exact integer timeline of binned stepping (SWIFT's `integertime_t`, Schaller et
/// al. 2016; Saitoh & Makino 2009 for the bins). Time is a count of quanta q; bin b is a step of
/// 2^b quanta, so bin `max_bin` is dt_max exactly and every bin nests in the ones above it. The
/// quantum is chosen per run, q = dt_max / 2^max_bin with max_bin = ceil(log2(dt_max / dt_min)),
/// so q <= dt_min and a particle whose step is at least dt_min always has a bin. A step of bin b
/// may start only at a multiple of 2^b quanta; a particle is due when the time reaches its end,
/// an integer compare. The engine's clock (1 ps ticks) follows as the rounded image of this
/// timeline, ticks_of(n) = round(n q / 1 ps); q >= dt_min / 2 >= 0.5 ns keeps the image strictly
/// increasing, and n q stays exact in double up to 2^53 quanta (>= 52 days of simulated time).
#include <bit>
#include <cmath>
#include <cstdint>

namespace sph {

struct BinTimeline {
    /// The scene's time keys lie in [1e-9, 1e6] s, so dt_max / dt_min < 2^50: 52 bins always do.
    static constexpr int kMaxBin = 52;
    double quantum = 0;   ///< q, s
    int max_bin = 0;      ///< bin of dt_max
    std::uint64_t now = 0;   ///< the due time of the last step that started on the timeline
    std::uint64_t next = 0;  ///< the earliest due time after `now` (the planned step's end)

    /// @brief The timeline of a run with steps in [dt_min, dt_max] (dt_min < dt_max, both > 0).
    static BinTimeline for_range(double dt_min, double dt_max) {
        BinTimeline t;
        t.max_bin = std::min(kMaxBin, std::max(0, int(std::ceil(std::log2(dt_max / dt_min)))));
        t.quantum = std::ldexp(dt_max, -t.max_bin);
        return t;
    }
    /// @brief Steps of 2^b quanta.
    static constexpr std::uint64_t length(int bin) { return std::uint64_t(1) << bin; }
    double seconds(std::uint64_t quanta) const { return double(quanta) * quantum; }
    /// @brief The largest bin whose step is at most `dt` seconds, clamped to [0, max_bin].
    int bin_for(double dt) const {
        if (!(dt >= quantum)) return 0;
        if (dt >= seconds(length(max_bin))) return max_bin;
        // floor(log2(dt / q)) from the integer part (exact: dt / q < 2^max_bin + 1 < 2^53)
        return std::bit_width(std::uint64_t(dt / quantum)) - 1;
    }
    /// @brief Whether a step of bin b may start at time n (n is a multiple of 2^b).
    static constexpr bool aligned(std::uint64_t n, int bin) { return (n & (length(bin) - 1)) == 0; }
    /// @brief The largest bin (<= cap) a step starting at n may have.
    static int largest_aligned_bin(std::uint64_t n, int cap) {
        return n == 0 ? cap : std::min(cap, std::countr_zero(n));
    }
    /// @brief The first multiple of 2^b strictly after n (where a woken particle's step ends).
    static constexpr std::uint64_t next_aligned(std::uint64_t n, int bin) { return ((n >> bin) + 1) << bin; }
};

}  // namespace sph
