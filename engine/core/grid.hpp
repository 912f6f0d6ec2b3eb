#pragma once
/// @file grid.hpp
/// @brief Uniform grid with cell size equal to the support radius, built in parallel, and
/// fixed-capacity neighbour lists that can be rebuilt for any subset of particles.
#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>

#include <tbb/parallel_for.h>
#include <vector>

#include "engine/core/types.hpp"

namespace sph {

/// @brief The candidates around a point: at most 9 contiguous ranges of sorted slots (one per
/// x-row of the 27 surrounding cells), empty ranges left out.
struct CandidateRanges {
    static constexpr int kMax = 9;
    std::array<Index, kMax> begin{}, end{};
    int count = 0;
    std::size_t total = 0;  ///< candidates over all ranges
};

/// @brief Dense uniform grid over a box. Cells are numbered x-fastest, so the three cells of
/// one x-row are contiguous in the sorted order and a 27-cell query is 9 contiguous ranges.
class UniformGrid {
public:
    UniformGrid() = default;
    /// @brief Grid covering `box` grown by one cell on every side; positions outside are
    /// clamped into the border cells (the run stops on such particles anyway). Throws
    /// InputError, naming `what`, the box, the cell count and its memory, when the grid would
    /// have kMaxCells cells or more. With `keep_coordinates` the grid also keeps the positions
    /// in its slot order, one array per axis (12 bytes a particle), which the search copies
    /// per cell instead of gathering them through the index (faster for the fluid search; the
    /// boundary's grid, whose candidates are rarely filled, does without: measured in
    /// docs/results/benchmarks.md).
    UniformGrid(const Aabb& box, Real cell_size, const std::string& what = "grid", bool keep_coordinates = false);

    /// Cells are indexed in 32 bits: at most this many (a 16 GiB cell table).
    static constexpr std::uint64_t kMaxCells = (std::uint64_t(1) << 32) - 2;

    /// @brief Sorts particle indices by cell (a counting sort, so ties keep index order and the
    /// result is deterministic, the same for any number of threads). O(N + cells); the cell keys
    /// and the coordinates are parallel. A query passes the particle set the grid was built
    /// from, which must not be reordered, shrunk or moved between the build and the query.
    void build(std::span<const Vec3> positions);

    /// @brief With `on`, every build also marks the cells whose 27-cell neighbourhood holds no
    /// particle (empty_around), so that a query of another particle set there (the boundary
    /// grid's fluid queries, about two in three of which meet no candidate on `dam_break_obstacles`)
    /// is answered by one lookup. Off by default: a set queried against itself is never empty.
    /// Costs one byte a cell (and two more while a build computes them).
    void mark_empty_neighbourhoods(bool on) { m_mark_empty = on; }
    /// @brief With `on`, every build also keeps each particle's cell (4 bytes a particle), so
    /// that in_built_cells can tell whether a later move left the grid as it is.
    void keep_cells(bool on) {
        m_keep_cells = on;
        if (!on) std::vector<Index>().swap(m_cell_of);
    }
    /// @brief Whether the particles [begin, end) of the set the grid was built from still lie in
    /// the cells they were sorted into: when every particle that moved since the build does,
    /// a build from the current positions gives this grid, bit for bit (the slots follow the
    /// cells, and within a cell the index order). False without keep_cells, after a set_drift,
    /// or when the set's size changed.
    bool in_built_cells(std::span<const Vec3> positions, std::size_t begin, std::size_t end) const;
    /// @brief The builds since construction (for the tests).
    std::uint64_t builds() const { return m_builds; }
    /// @brief Whether no particle lies in the 27 cells around cell c (so no query there has a
    /// candidate); false when the grid does not mark them or carries a drift.
    bool empty_around(std::int64_t c) const { return m_drift == 0 && !m_near.empty() && !m_near[std::size_t(c)]; }

    /// @brief Declares that no particle has moved more than `drift` (< cell_size() / 2) since the
    /// last build, so the grid can serve the moved particles without a rebuild (binned
    /// stepping's sparse steps: FluidGridSystem). Its cells and coordinates stay those of the
    /// build; for_each_candidate and build_neighbour_lists then widen their reach by `drift`,
    /// test the candidates at the positions they are given, and return exactly what a grid
    /// built from those positions returns, in the same order (by cell, then index). The range
    /// queries (for_each_candidate_range, candidate_ranges) describe the grid as built. A
    /// build resets the drift to 0.
    void set_drift(Real drift);
    Real drift() const { return m_drift; }

    /// @brief The slot ranges of every cell within `reach` of x along each axis, in slot order:
    /// up to 4 x 4 rows of up to 4 cells while reach < 1.5 cell_size(), in two parts of at most
    /// 8 rows (reach == cell_size() gives the 27 cells of candidate_ranges).
    struct WideRanges {
        CandidateRanges part[2];
        std::size_t total = 0;
    };
    WideRanges ranges_within(const Vec3& x, Real reach) const;

    /// Readable slots past the last particle in sorted_index() (particle 0), and far points past
    /// the last candidate in a CandidateCache, so a vectorised loop may load a whole vector.
    static constexpr std::size_t kPadding = 16;

    /// The cell of x along each axis, floor((x - origin) / cell_size) clamped to the grid. The
    /// conversion truncates instead of calling floor: the two differ only below 0, where the
    /// clamp gives 0 either way (floor is a call, or a long sequence, without SSE4.1).
    [[gnu::always_inline]] Eigen::Vector3i cell_coords(const Vec3& x) const {
        Eigen::Vector3i c;
        for (int a = 0; a < 3; ++a) {
            const int v = static_cast<int>((x[a] - m_origin[a]) * m_inv_cell);
            c[a] = std::clamp(v, 0, m_dims[a] - 1);
        }
        return c;
    }
    [[gnu::always_inline]] std::int64_t cell_index(const Eigen::Vector3i& c) const {
        return c[0] + std::int64_t(m_dims[0]) * (c[1] + std::int64_t(m_dims[1]) * c[2]);
    }
    /// @brief The cell a point falls in (clamped to the grid).
    std::int64_t cell_of(const Vec3& x) const { return cell_index(cell_coords(x)); }

    /// @brief Calls fn(j, x_j) for every particle j in the 27 cells around x (a superset of
    /// the particles within one cell size of x); `positions` are the particles the grid was
    /// built from.
    template <class Fn>
    void for_each_candidate(const Vec3& x, std::span<const Vec3> positions, Fn&& fn) const {
        if (m_drift > 0) {  // the particles whose current cell is among the 27, in a fresh grid's order
            std::vector<Index> found;  // the caller's own (fn may query again)
            drifted_candidates(x, positions, found);
            for (Index j : found) fn(j, positions[j]);
            return;
        }
        const Eigen::Vector3i c = cell_coords(x);
        const int x0 = std::max(c[0] - 1, 0), x1 = std::min(c[0] + 1, m_dims[0] - 1);
        for (int z = std::max(c[2] - 1, 0); z <= std::min(c[2] + 1, m_dims[2] - 1); ++z)
            for (int y = std::max(c[1] - 1, 0); y <= std::min(c[1] + 1, m_dims[1] - 1); ++y) {
                const std::int64_t row = cell_index({0, y, z});
                const Index b = cell_start(row + x0), e = cell_start(row + x1 + 1);
                for (Index k = b; k < e; ++k) fn(m_sorted_index[k], positions[m_sorted_index[k]]);
            }
    }

    /// @brief Calls fn(begin, end) for the 9 contiguous ranges of sorted slots that hold the 27
    /// cells around x (the same candidates, in the same order, as for_each_candidate); the
    /// slots index sorted_index().
    template <class Fn>
    void for_each_candidate_range(const Vec3& x, Fn&& fn) const {
        const Eigen::Vector3i c = cell_coords(x);
        const int x0 = std::max(c[0] - 1, 0), x1 = std::min(c[0] + 1, m_dims[0] - 1);
        for (int z = std::max(c[2] - 1, 0); z <= std::min(c[2] + 1, m_dims[2] - 1); ++z)
            for (int y = std::max(c[1] - 1, 0); y <= std::min(c[1] + 1, m_dims[1] - 1); ++y) {
                const std::int64_t row = cell_index({0, y, z});
                fn(cell_start(row + x0), cell_start(row + x1 + 1));
            }
    }
    /// Particle index by sorted slot (particle_count() entries; kPadding readable ones follow).
    /// @brief The 27 cells around x as contiguous slot ranges (what for_each_candidate_range visits).
    CandidateRanges candidate_ranges(const Vec3& x) const {
        CandidateRanges r;
        for_each_candidate_range(x, [&](Index b, Index e) {
            if (e > b) {
                r.begin[r.count] = b;
                r.end[r.count] = e;
                ++r.count;
                r.total += e - b;
            }
        });
        return r;
    }
    std::span<const Index> sorted_index() const { return {m_sorted_index.data(), m_count}; }
    /// Coordinates by slot, one array per axis (kPadding far points follow the last), or null
    /// when the grid does not keep them.
    const Real* sorted_x() const { return m_sx.empty() ? nullptr : m_sx.data(); }
    const Real* sorted_y() const { return m_sy.empty() ? nullptr : m_sy.data(); }
    const Real* sorted_z() const { return m_sz.empty() ? nullptr : m_sz.data(); }
    /// First slot of cell c (c in [0, cell_count()]; cell_count() gives particle_count()).
    Index cell_start(std::int64_t c) const {
        return m_wide.empty() ? m_chunk_start[std::size_t(c) >> kChunkBits] + m_offset[std::size_t(c)] : m_wide[std::size_t(c)];
    }

    const Eigen::Vector3i& dims() const { return m_dims; }
    const Vec3& origin() const { return m_origin; }
    Real cell_size() const { return m_cell; }
    std::size_t cell_count() const { return m_cells; }
    std::size_t particle_count() const { return m_count; }
    std::size_t bytes() const;
    /// The cell table alone (a packed start per cell, or the 32-bit fallback with it).
    std::size_t table_bytes() const;

private:
    /// for_each_candidate of a drifted grid: the particles whose cell at `positions` is one of
    /// the 27 around x, by cell and then index, into `out`.
    void drifted_candidates(const Vec3& x, std::span<const Vec3> positions, std::vector<Index>& out) const;

    Real m_drift = 0;
    Vec3 m_origin = Vec3::Zero();
    Real m_cell = 1, m_inv_cell = 1;
    Eigen::Vector3i m_dims{1, 1, 1};
    /// The first slot of each cell (cells + 1 entries) as a 32-bit start per chunk of
    /// 2^kChunkBits cells plus a 16-bit offset per cell: 2.25 bytes a cell instead of 4 (the
    /// table spans the whole domain, mostly air). A build whose chunk holds 65,536 particles or
    /// more (particles piled into one place) keeps a 32-bit start per cell instead (m_wide).
    static constexpr unsigned kChunkBits = 4;
    std::size_t m_cells = 0;
    std::vector<Index> m_chunk_start;
    std::vector<std::uint16_t> m_offset;
    std::vector<Index> m_wide;
    std::size_t m_count = 0;
    std::vector<Index> m_sorted_index;    ///< particle_count() + kPadding
    bool m_keep_coordinates = false;
    std::vector<Real> m_sx, m_sy, m_sz;   ///< with keep_coordinates: particle_count() + kPadding each
    bool m_mark_empty = false;
    std::vector<std::uint8_t> m_near;     ///< with mark_empty_neighbourhoods: 1 where the 27 cells hold a particle
    bool m_keep_cells = false;
    std::vector<Index> m_cell_of;         ///< with keep_cells: each particle's cell at the build
    std::uint64_t m_builds = 0;
};

/// @brief The candidates of one cell's 27-cell neighbourhood gathered from the grid's particle
/// set into contiguous arrays (one per axis and the particle index, in the grid's slot order), padded
/// with far points to a whole vector. Queries in one cell (mostly consecutive in a z-ordered
/// set) then filter one contiguous array instead of 9 ranges each, and a query whose
/// neighbourhood is empty (most fluid particles against the boundary) costs one comparison.
struct CandidateCache {
    std::int64_t cell = -1;  ///< the cell whose neighbourhood is held (-1: none)
    std::size_t count = 0;   ///< candidates; the arrays hold count + UniformGrid::kPadding
    std::vector<Real> x, y, z;
    std::vector<Index> index;
    /// @brief Holds the neighbourhood of `cell`, the cell of `at`; `positions` are the particles
    /// the grid was built from.
    void fill(const UniformGrid& grid, std::span<const Vec3> positions, const Vec3& at, std::int64_t cell);
};

/// @brief Neighbour lists of query particles, in one of two layouts:
/// * slab (capacity > 0): a fixed capacity per query particle, so the lists of any subset can
///   be rebuilt in place while the others keep theirs (individual stepping). Capacity grows
///   (and every list is rebuilt) when a particle has more neighbours.
/// * compact (capacity == 0): every list rebuilt at once (global, constant, PCISPH), stored
///   back to back in blocks of kBlock query particles, about 2.5x smaller than a slab; or the
///   lists of a subset only (binned stepping), every other list empty. A list is known by its
///   end in the block alone (it begins where the previous one of its block ends): 4 bytes per
///   query particle.
/// Either way a list may be read a whole vector (kSlack entries) past its end.
struct NeighbourLists {
    static constexpr std::size_t kBlock = 256;  ///< query particles per compact block
    static constexpr std::size_t kSlack = 16;   ///< readable entries after every list
    Index capacity = 0;          ///< slab: entries per query particle (a multiple of 16); 0: compact
    std::vector<Index> count;    ///< slab: entries per query particle
    std::vector<Index> indices;  ///< slab: count.size() * capacity
    std::vector<Index> end;      ///< compact: one past the last entry of each list in its block
    std::vector<std::vector<Index>> blocks;  ///< compact: the lists of particles [kBlock b, kBlock (b + 1))
    /// Compact: the particles of the last subset build, ascending (the only non-empty lists);
    /// empty after a build of every list. Lets the next subset build empty just their blocks.
    std::vector<Index> queried;

    bool compact() const { return capacity == 0; }
    /// Query particles the lists are for.
    std::size_t rows() const { return compact() ? end.size() : count.size(); }
    /// Compact: where list i begins in block i / kBlock.
    Index begin_of(Index i) const { return i % kBlock ? end[i - 1] : Index(0); }
    Index size_of(Index i) const { return compact() ? end[i] - begin_of(i) : count[i]; }
    std::span<const Index> of(Index i) const {
        if (capacity) return {indices.data() + std::size_t(i) * capacity, count[i]};
        const Index b = begin_of(i);
        return {blocks[i / kBlock].data() + b, end[i] - b};
    }
    /// Every list's length, in query order (the checkpoint form).
    std::vector<Index> counts() const;
    std::size_t bytes() const;
    std::size_t total() const;
    /// @brief Follows a permutation of the query particles (new[i] = old[perm[i]]); when
    /// `remap_entries`, the entries refer to the same particle set and are renumbered too.
    /// Keeps the lists of particles that are not rebuilt this step valid after a sort.
    void permute(std::span<const Index> perm, bool remap_entries);
    /// @brief Every list, one after another in query order (the checkpoint form).
    std::vector<Index> concatenated() const;
    /// @brief The compact layout from counts and concatenated lists (as counts() and
    /// concatenated() give); `queried` becomes the particles with a non-empty list.
    void assign_compact(std::span<const Index> counts, std::span<const Index> entries);
};

/// @brief Indices i in [0, n) with pred(i), ascending; parallel and deterministic.
template <class Pred>
std::vector<Index> collect_indices(std::size_t n, Pred&& pred);

/// @brief Which particles to (re)build lists for: all of them, or an explicit subset.
struct QuerySubset {
    std::span<const Index> indices;  ///< ascending; empty with all == true means every particle
    bool all = true;
    /// Whether the other particles keep their lists (individual stepping reads them): the slab
    /// layout. Otherwise (binned stepping) the subset's lists are built compact and every other
    /// list is empty.
    bool keep_others = true;
};

/// @brief Builds the lists of the query particles against the particles of `grid` (at
/// `grid_positions`, the set it was built from): every j with |x_i - x_j|^2 < radius^2, in the
/// grid's sorted order, excluding j == i when `exclude_self` (query and grid are the same set).
/// Equals brute force exactly. `simd` takes
/// the vectorised filter (neighbour_filter.hpp; float builds), else the scalar one: the same
/// lists either way. Every list (subset.all) gives the compact layout, a subset the slab one.
void build_neighbour_lists(const UniformGrid& grid, std::span<const Vec3> grid_positions,
                           std::span<const Vec3> query_positions, Real radius, bool exclude_self,
                           const QuerySubset& subset, NeighbourLists& lists, bool simd);

/// @brief Permutation that orders particles along the z-order (Morton) curve of their grid
/// cells, ties broken by current index: new[i] = old[perm[i]].
std::vector<Index> zorder_permutation(const UniformGrid& grid, std::span<const Vec3> positions);

template <class Pred>
std::vector<Index> collect_indices(std::size_t n, Pred&& pred) {
    constexpr std::size_t kBlock = 4096;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<std::vector<Index>> parts(blocks);
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
        // Branch-free (each index written, the count advanced by the predicate): a branch on a
        // predicate true for a scattered share of the particles mispredicts often.
        const std::size_t begin = b * kBlock, end = std::min(n, begin + kBlock);
        auto& part = parts[b];
        part.resize(end - begin);
        std::size_t kept = 0;
        for (std::size_t i = begin; i < end; ++i) {
            part[kept] = Index(i);
            kept += std::size_t(bool(pred(i)));
        }
        part.resize(kept);
    });
    std::vector<Index> out;
    for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
    return out;
}

}  // namespace sph
