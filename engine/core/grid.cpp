#include "engine/core/grid.hpp"

#include "engine/core/neighbour_filter.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <atomic>
#include <limits>

namespace sph {

UniformGrid::UniformGrid(const Aabb& box, Real cell_size) : m_cell(cell_size), m_inv_cell(Real(1) / cell_size) {
    for (int a = 0; a < 3; ++a) {
        m_origin[a] = Real(box.min[a]) - cell_size;
        const double cells = std::ceil((box.max[a] - box.min[a]) / cell_size) + 2.0;
        m_dims[a] = std::max(1, static_cast<int>(cells));
    }
    m_cell_start.assign(std::size_t(m_dims.prod()) + 1, 0);
}

std::size_t UniformGrid::bytes() const {
    return m_keys.capacity() * sizeof(std::uint64_t) + m_cell_start.capacity() * sizeof(Index) +
           m_sorted_index.capacity() * sizeof(Index) + 3 * m_sx.capacity() * sizeof(Real);
}

void UniformGrid::build(std::span<const Vec3> positions) {
    const std::size_t n = positions.size();
    m_keys.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
            m_keys[i] = (std::uint64_t(cell_index(cell_coords(positions[i]))) << 32) | i;
    });
    // Keys are unique, so the order is deterministic whatever the thread count.
    tbb::parallel_sort(m_keys.begin(), m_keys.end());
    m_count = n;
    m_sorted_index.resize(n + kPadding, 0);
    // The padding slots hold a point far outside every query's range, so a whole vector
    // loaded at the end of the last range filters them out.
    m_sx.resize(n + kPadding, std::numeric_limits<Real>::max());
    m_sy.resize(n + kPadding, std::numeric_limits<Real>::max());
    m_sz.resize(n + kPadding, std::numeric_limits<Real>::max());
    std::fill(m_sx.begin() + n, m_sx.end(), std::numeric_limits<Real>::max());
    std::fill(m_sy.begin() + n, m_sy.end(), std::numeric_limits<Real>::max());
    std::fill(m_sz.begin() + n, m_sz.end(), std::numeric_limits<Real>::max());
    const std::size_t cells = cell_count();
    // cell_start[c] = first sorted slot whose cell >= c, for every c (empty cells included),
    // so that a row of cells is one contiguous range.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = Index(m_keys[k] & 0xffffffffu);
            m_sorted_index[k] = i;
            m_sx[k] = positions[i].x();
            m_sy[k] = positions[i].y();
            m_sz[k] = positions[i].z();
            const std::uint64_t c = m_keys[k] >> 32;
            const std::uint64_t prev = k == 0 ? 0 : (m_keys[k - 1] >> 32) + 1;
            for (std::uint64_t cc = prev; cc <= c; ++cc) m_cell_start[cc] = Index(k);
        }
    });
    const std::uint64_t last = n == 0 ? 0 : (m_keys[n - 1] >> 32) + 1;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(last, cells + 1, 16384), [&](const auto& r) {
        for (std::size_t c = r.begin(); c < r.end(); ++c) m_cell_start[c] = Index(n);
    });
}

std::size_t NeighbourLists::total() const {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count.size(), 8192), std::size_t(0),
        [&](const auto& r, std::size_t s) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) s += count[i];
            return s;
        },
        std::plus<>());
}

void build_neighbour_lists(const UniformGrid& grid, std::span<const Vec3> query_positions,
                           Real radius, bool exclude_self, const QuerySubset& subset,
                           NeighbourLists& lists, bool simd) {
    const std::size_t n = query_positions.size();
    const Real r2 = radius * radius;
    if (lists.count.size() != n) lists.count.assign(n, 0);
    if (lists.capacity == 0) lists.capacity = 48;
    const std::size_t m = subset.all ? n : subset.indices.size();
    constexpr Index kNoSelf = ~Index(0);
    for (;;) {
        if (lists.indices.size() != n * std::size_t(lists.capacity))
            lists.indices.resize(n * std::size_t(lists.capacity));
        std::atomic<Index> overflow{0};
        const Index cap = lists.capacity;
        const std::span<const Index> sorted_index = grid.sorted_index();
        const Real* sx = grid.sorted_x();
        const Real* sy = grid.sorted_y();
        const Real* sz = grid.sorted_z();
        tbb::enumerable_thread_specific<std::vector<Index>> scratch;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 256), [&](const auto& r) {
            Index local_max = 0;
            std::vector<Index>& found = scratch.local();
            for (std::size_t q = r.begin(); q < r.end(); ++q) {
                const Index i = subset.all ? Index(q) : subset.indices[q];
                const Vec3 xi = query_positions[i];
                Index* out = lists.indices.data() + std::size_t(i) * cap;
                std::size_t candidates = 0;
                grid.for_each_candidate_range(xi, [&](Index b, Index e) { candidates += e - b; });
                // One vector of slack for the vectorised filter's whole-vector stores.
                if (found.size() < candidates + UniformGrid::kPadding) found.resize(2 * candidates + UniformGrid::kPadding);
                Index* dst = found.data();
                Index c = 0;
                if (simd) {
                    c = filter_candidates_simd(grid, xi, exclude_self ? i : kNoSelf, r2, dst);
                } else {
                    // Branch-free scalar filter: every candidate is written and the cursor
                    // advances only when it is in range, so the loop has no data-dependent
                    // branch (the in-range test is a coin toss for about half the candidates
                    // once the start lattice has become disordered).
                    grid.for_each_candidate_range(xi, [&](Index b, Index e) {
                        for (Index k = b; k < e; ++k) {
                            const Index j = sorted_index[k];
                            const Vec3 d = xi - Vec3(sx[k], sy[k], sz[k]);
                            dst[c] = j;
                            c += Index(d.squaredNorm() < r2) & Index(!(exclude_self && j == i));
                        }
                    });
                }
                std::copy_n(found.data(), std::min(c, cap), out);
                lists.count[i] = c;
                local_max = std::max(local_max, c);
            }
            Index cur = overflow.load();
            while (local_max > cap && local_max > cur && !overflow.compare_exchange_weak(cur, local_max)) {
            }
        });
        if (overflow.load() == 0) return;
        // Grow to the next multiple of 16 with 25 % head room; every list is rebuilt, since
        // the slab layout changes.
        lists.capacity = ((overflow.load() * 5 / 4) + 15) / 16 * 16;
        lists.indices.clear();
        if (!subset.all) {
            // The other particles' lists must move to the new layout too: rebuild them all.
            build_neighbour_lists(grid, query_positions, radius, exclude_self, QuerySubset{}, lists, simd);
            return;
        }
    }
}

void NeighbourLists::permute(std::span<const Index> perm, bool remap_entries) {
    const std::size_t n = count.size();
    if (n == 0 || perm.size() != n) return;
    std::vector<Index> inverse;
    if (remap_entries) {
        inverse.resize(n);
        for (std::size_t i = 0; i < n; ++i) inverse[perm[i]] = Index(i);
    }
    std::vector<Index> new_count(n), new_indices(indices.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Index from = perm[i];
            const Index c = std::min(count[from], capacity);
            new_count[i] = count[from];
            const Index* src = indices.data() + std::size_t(from) * capacity;
            Index* dst = new_indices.data() + i * capacity;
            for (Index k = 0; k < c; ++k) dst[k] = remap_entries ? inverse[src[k]] : src[k];
        }
    });
    count.swap(new_count);
    indices.swap(new_indices);
}

namespace {
std::uint64_t spread_bits(std::uint64_t v) {  // 21 bits -> every third bit
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}
}  // namespace

std::vector<Index> zorder_permutation(const UniformGrid& grid, std::span<const Vec3> positions) {
    const std::size_t n = positions.size();
    std::vector<std::pair<std::uint64_t, Index>> keys(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Eigen::Vector3i c = grid.cell_coords(positions[i]);
            const std::uint64_t m = spread_bits(std::uint64_t(c[0])) | spread_bits(std::uint64_t(c[1])) << 1 |
                                    spread_bits(std::uint64_t(c[2])) << 2;
            keys[i] = {m, Index(i)};
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    std::vector<Index> perm(n);
    for (std::size_t i = 0; i < n; ++i) perm[i] = keys[i].second;
    return perm;
}

}  // namespace sph
