#pragma once
/// @file timeline.hpp
/// @brief The exact integer timeline of binned stepping (SWIFT's `integertime_t`, Schaller et
/// al. 2016; Saitoh & Makino 2009 for the bins). Time is a count of quanta q; bin b is a step of
/// 2^b quanta, so bin `max_bin` is dt_max exactly and every bin nests in the ones above it. The
/// quantum is chosen per run, q = dt_max / 2^max_bin with max_bin = ceil(log2(dt_max / dt_min)),
/// so q <= dt_min and a particle whose step is at least dt_min always has a bin. A step of bin b
/// may start only at a multiple of 2^b quanta; a particle is due when the time reaches its end,
/// an integer compare. The engine's clock (1 ps ticks) follows as the rounded image of this
/// timeline, origin + round(n q / 1 ps); q >= dt_min / 2 >= 0.5 ns keeps the image strictly
/// increasing, and n q stays exact in double up to 2^53 quanta (>= 52 days of simulated time).
///
/// Rebasing: when every particle is due at once (a full synchronisation: at the latest at every
/// multiple of the top bin's step) no step is in flight, so the timeline may start afresh at
/// that time with another quantum. rebased() puts a bin at `headroom` times the shortest step
/// wanted then, unless the fixed ladder dt_max / 2^k already has one as close: with a fixed
/// ladder the shortest step is rounded down by up to 2x (28 % on average over a log-uniform
/// spread), which is what a run whose particles share one step (the acoustic bound) pays on
/// every step. docs/methods.md, "Binned stepping", has the measurements.
#include <bit>
#include <cmath>
#include <cstdint>

namespace sph {

struct BinTimeline {
    /// The scene's time keys lie in [1e-9, 1e6] s, so dt_max / dt_min < 2^50: 52 bins always do.
    static constexpr int kMaxBin = 52;
    double quantum = 0;   ///< q, s
    int max_bin = 0;      ///< the top bin (its step is at most dt_max)
    std::int64_t origin = 0;  ///< engine tick of quantum 0 (moved by rebasing)
    std::uint64_t now = 0;   ///< the due time of the last step that started on the timeline
    std::uint64_t next = 0;  ///< the earliest due time after `now` (the planned step's end)

    /// @brief The timeline of a run with steps in [dt_min, dt_max] (dt_min < dt_max, both > 0).
    static BinTimeline for_range(double dt_min, double dt_max) {
        BinTimeline t;
        t.max_bin = std::min(kMaxBin, std::max(0, int(std::ceil(std::log2(dt_max / dt_min)))));
        t.quantum = std::ldexp(dt_max, -t.max_bin);
        return t;
    }
    /// @brief The timeline restarted at engine tick `origin` so that `shortest` (the shortest
    /// step wanted now, <= dt_max) falls on a bin within `headroom` of it: the fixed ladder
    /// dt_max / 2^k when its bin below `shortest` is at least headroom x shortest, else a ladder
    /// through headroom x shortest. Either way q <= dt_min and the top bin's step is <= dt_max.
    static BinTimeline rebased(double shortest, double headroom, double dt_min, double dt_max, std::int64_t origin) {
        BinTimeline t = for_range(dt_min, dt_max);
        t.origin = origin;
        const double fixed = t.seconds(length(t.bin_for(shortest)));
        const double step = std::max(dt_min, headroom * shortest);
        if (fixed >= step || step >= dt_max) return t;
        const int below = std::max(0, int(std::ceil(std::log2(step / dt_min))));  // bins under `step`
        const int above = std::max(0, int(std::floor(std::log2(dt_max / step))));
        t.max_bin = std::min(kMaxBin, below + above);
        t.quantum = std::ldexp(step, -below);
        return t;
    }
    /// @brief Steps of 2^b quanta.
    static constexpr std::uint64_t length(int bin) { return std::uint64_t(1) << bin; }
    double seconds(std::uint64_t quanta) const { return double(quanta) * quantum; }
    /// @brief The largest bin whose step is at most `dt` seconds, clamped to [0, max_bin].
    int bin_for(double dt) const {
        if (!(dt >= quantum)) return 0;
        if (dt >= seconds(length(max_bin))) return max_bin;
        // floor(log2(dt / q)), exactly, from the binary exponents and mantissas of dt and q
        // (both positive and normal): 2^(e_dt - e_q) times the ratio of the mantissas, which is
        // below 1 exactly when dt's mantissa is the smaller.
        const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
        constexpr std::uint64_t kMantissa = (std::uint64_t(1) << 52) - 1;
        const std::uint64_t d = bits(dt), q = bits(quantum);
        const int e = int(d >> 52) - int(q >> 52);
        return e - int((d & kMantissa) < (q & kMantissa));
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
