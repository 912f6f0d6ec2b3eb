#include "engine/core/grid.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/neighbour_filter.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

namespace sph {

UniformGrid::UniformGrid(const Aabb& box, Real cell_size, const std::string& what, bool keep_coordinates)
    : m_cell(cell_size), m_inv_cell(Real(1) / cell_size), m_keep_coordinates(keep_coordinates) {
    double dims[3], total = 1;
    for (int a = 0; a < 3; ++a) {
        m_origin[a] = Real(box.min[a]) - cell_size;
        dims[a] = std::max(1.0, std::ceil((box.max[a] - box.min[a]) / cell_size) + 2.0);
        total *= dims[a];
    }
    // Cells are numbered with 32-bit indices (and the table holds one 32-bit start per cell),
    // so a box too large for its cell size is refused before anything is allocated.
    if (!(total < double(kMaxCells))) {
        std::ostringstream os;
        os << "the " << what << " over [" << box.min.transpose() << "] - [" << box.max.transpose() << "] m with cells of "
           << cell_size << " m would have " << dims[0] << " x " << dims[1] << " x " << dims[2] << " = " << total
           << " cells (" << total * sizeof(Index) / double(1 << 30) << " GiB for its cell table); at most " << kMaxCells
           << " cells are supported: give the scene a smaller `domain`, or larger particles";
        throw InputError(os.str());
    }
    for (int a = 0; a < 3; ++a) m_dims[a] = static_cast<int>(dims[a]);
    m_cells = std::size_t(total);
    m_chunk_start.assign((m_cells >> kChunkBits) + 1, 0);
    m_offset.assign(m_cells + 1, 0);
}

std::size_t UniformGrid::table_bytes() const {
    return (m_chunk_start.capacity() + m_wide.capacity()) * sizeof(Index) + m_offset.capacity() * sizeof(std::uint16_t);
}

std::size_t UniformGrid::bytes() const {
    return (m_chunk_start.capacity() + m_wide.capacity() + m_sorted_index.capacity() + m_cell_of.capacity()) * sizeof(Index) +
           m_offset.capacity() * sizeof(std::uint16_t) + (m_sx.capacity() + m_sy.capacity() + m_sz.capacity()) * sizeof(Real) +
           m_near.capacity();
}

bool UniformGrid::in_built_cells(std::span<const Vec3> positions, std::size_t begin, std::size_t end) const {
    if (!m_keep_cells || m_drift > 0 || positions.size() != m_count || m_cell_of.size() != m_count || end > m_count)
        return false;
    for (std::size_t i = begin; i < end; ++i)
        if (Index(cell_index(cell_coords(positions[i]))) != m_cell_of[i]) return false;
    return true;
}

void UniformGrid::set_drift(Real drift) {
    if (!(drift >= 0 && drift < Real(0.5) * m_cell))
        throw std::logic_error("UniformGrid::set_drift: the drift must lie in [0, cell size / 2)");
    m_drift = drift;
}

UniformGrid::WideRanges UniformGrid::ranges_within(const Vec3& x, Real reach) const {
    const Eigen::Vector3i lo = cell_coords(x - Vec3::Constant(reach)), hi = cell_coords(x + Vec3::Constant(reach));
    WideRanges w;
    int rows = 0;
    for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y) {
            const std::int64_t row = cell_index({0, y, z});
            const Index b = cell_start(row + lo[0]), e = cell_start(row + hi[0] + 1);
            if (e == b) continue;
            if (rows == 16) throw std::logic_error("UniformGrid::ranges_within: more than 16 rows of cells (reach too long)");
            CandidateRanges& r = w.part[rows++ / 8];
            r.begin[r.count] = b;
            r.end[r.count] = e;
            ++r.count;
            r.total += e - b;
            w.total += e - b;
        }
    return w;
}

namespace {

/// (cell, index) as one sortable key: a fresh grid lists its candidates in this order (cells
/// ascending, x fastest, and within a cell by index, the counting sort being stable).
std::uint64_t cell_key(std::int64_t cell, Index j) { return std::uint64_t(cell) << 32 | j; }

/// Sorts keys that are nearly in order (a drifted grid's candidates: only those that changed
/// cell since the build are out of place), in O(n + displacements).
void insertion_sort(std::uint64_t* k, std::size_t n) {
    for (std::size_t i = 1; i < n; ++i) {
        const std::uint64_t v = k[i];
        std::size_t j = i;
        for (; j > 0 && k[j - 1] > v; --j) k[j] = k[j - 1];
        k[j] = v;
    }
}

}  // namespace

void UniformGrid::drifted_candidates(const Vec3& x, std::span<const Vec3> positions, std::vector<Index>& out) const {
    thread_local std::vector<std::uint64_t> keys;  // used and done with before returning
    keys.clear();
    // A particle now in one of the 27 cells around x's was built at most one cell further out
    // (drift < cell size), so the stale cells two out are searched.
    const Eigen::Vector3i c = cell_coords(x);
    const int x0 = std::max(c[0] - 2, 0), x1 = std::min(c[0] + 2, m_dims[0] - 1);
    for (int z = std::max(c[2] - 2, 0); z <= std::min(c[2] + 2, m_dims[2] - 1); ++z)
        for (int y = std::max(c[1] - 2, 0); y <= std::min(c[1] + 2, m_dims[1] - 1); ++y) {
            const std::int64_t row = cell_index({0, y, z});
            for (Index k = cell_start(row + x0), e = cell_start(row + x1 + 1); k < e; ++k) {
                const Index j = m_sorted_index[k];
                const Eigen::Vector3i cj = cell_coords(positions[j]);
                if ((cj - c).cwiseAbs().maxCoeff() <= 1) keys.push_back(cell_key(cell_index(cj), j));
            }
        }
    insertion_sort(keys.data(), keys.size());
    out.resize(keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) out[k] = Index(keys[k]);
}

void UniformGrid::build(std::span<const Vec3> positions) {
    m_drift = 0;
    const std::size_t n = positions.size();
    const std::size_t cells = cell_count();
    m_count = n;
    ++m_builds;
    // Scratch, uninitialised (zeroing it cost a pass over 4 bytes a particle), freed on return;
    // with keep_cells the member array instead.
    std::unique_ptr<Index[]> scratch;
    if (m_keep_cells)
        m_cell_of.resize(n);
    else
        scratch = std::make_unique_for_overwrite<Index[]>(n);
    Index* const cell_of = m_keep_cells ? m_cell_of.data() : scratch.get();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) cell_of[i] = Index(cell_index(cell_coords(positions[i])));
    });
    // Counting sort: particles per cell, then each particle in index order to the next free slot
    // of its cell (so ties keep index order). next[c + 1] counts cell c; the prefix sums make
    // next[c] the first slot of cell c, and the scatter advances it to the cell's end, the first
    // slot of c + 1: start(c) = next[c - 1] afterwards, no pass to shift the table back. Serial:
    // the build runs beside the boundary's grid and search, where a histogram per thread cost
    // more than it saved (docs/results/benchmarks.md).
    std::vector<Index> next_scratch(cells + 1, 0);
    Index* const next = next_scratch.data();
    for (std::size_t i = 0; i < n; ++i) ++next[cell_of[i] + 1];
    for (std::size_t c = 1; c <= cells; ++c) next[c] += next[c - 1];
    m_sorted_index.resize(n + kPadding);
    std::fill(m_sorted_index.begin() + std::ptrdiff_t(n), m_sorted_index.end(), Index(0));  // readable: particle 0
    for (std::size_t i = 0; i < n; ++i) m_sorted_index[next[cell_of[i]]++] = Index(i);
    const Index* const cell_end = next;  // cell_end[c]: the end of cell c < cells (the last cell's is n)
    auto start_of = [&](std::size_t c) { return c == 0 ? Index(0) : next[c - 1]; };
    if (m_mark_empty) {
        // The occupied cells dilated by one cell along x, then y, then z: the 27-cell max, in
        // three passes over the cells.
        std::vector<std::uint8_t> a(cells), b(cells);
        for (std::size_t c = 0; c < cells; ++c) a[c] = cell_end[c] > start_of(c);
        const std::size_t nx = std::size_t(m_dims[0]), ny = std::size_t(m_dims[1]), nz = std::size_t(m_dims[2]);
        const std::size_t nxy = nx * ny;
        for (std::size_t row = 0; row < ny * nz; ++row) {  // along x, within each row of cells
            const std::uint8_t* in = a.data() + row * nx;
            std::uint8_t* out = b.data() + row * nx;
            for (std::size_t x = 0; x < nx; ++x)
                out[x] = in[x] | (x > 0 ? in[x - 1] : 0) | (x + 1 < nx ? in[x + 1] : 0);
        }
        for (std::size_t z = 0; z < nz; ++z)  // along y: whole rows of cells at once
            for (std::size_t y = 0; y < ny; ++y) {
                const std::uint8_t* in = b.data() + z * nxy + y * nx;
                std::uint8_t* out = a.data() + z * nxy + y * nx;
                for (std::size_t x = 0; x < nx; ++x)
                    out[x] = in[x] | (y > 0 ? in[x - nx] : 0) | (y + 1 < ny ? in[x + nx] : 0);
            }
        for (std::size_t z = 0; z < nz; ++z) {  // along z: whole planes
            const std::uint8_t* in = a.data() + z * nxy;
            std::uint8_t* out = b.data() + z * nxy;
            for (std::size_t c = 0; c < nxy; ++c)
                out[c] = in[c] | (z > 0 ? in[c - nxy] : 0) | (z + 1 < nz ? in[c + nxy] : 0);
        }
        m_near.swap(b);
    } else {
        std::vector<std::uint8_t>().swap(m_near);
    }
    // Pack: per chunk of 16 cells its first start, then each cell's offset from it (cells + 1
    // starts, the last one n).
    constexpr std::size_t kChunk = std::size_t(1) << kChunkBits;
    Index widest = 0;
    for (std::size_t q = 0, c0 = 0; c0 <= cells; ++q, c0 += kChunk) {
        const Index base = start_of(c0);
        m_chunk_start[q] = base;
        const std::size_t c1 = std::min(cells + 1, c0 + kChunk);
        for (std::size_t c = c0; c < c1; ++c) m_offset[c] = std::uint16_t(start_of(c) - base);
        widest = std::max(widest, start_of(c1 - 1) - base);  // starts rise within a chunk
    }
    if (widest > 0xffff) {
        m_wide.resize(cells + 1);
        for (std::size_t c = 0; c <= cells; ++c) m_wide[c] = start_of(c);
    } else {
        std::vector<Index>().swap(m_wide);
    }
    if (m_keep_coordinates) {
        // The padding slots hold a point far outside every query's range, so a whole vector
        // loaded at the end of the last range filters them out.
        for (auto* axis : {&m_sx, &m_sy, &m_sz}) {
            axis->resize(n + kPadding);
            std::fill(axis->begin() + std::ptrdiff_t(n), axis->end(), std::numeric_limits<Real>::max());
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
            for (std::size_t k = r.begin(); k < r.end(); ++k) {
                const Vec3& x = positions[m_sorted_index[k]];
                m_sx[k] = x.x();
                m_sy[k] = x.y();
                m_sz[k] = x.z();
            }
        });
    }
}

std::size_t NeighbourLists::bytes() const {
    std::size_t b = (count.capacity() + indices.capacity() + end.capacity() + queried.capacity()) * sizeof(Index);
    for (const auto& block : blocks) b += block.capacity() * sizeof(Index);
    return b;
}

std::size_t NeighbourLists::total() const {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, rows(), 8192), std::size_t(0),
        [&](const auto& r, std::size_t s) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) s += size_of(Index(i));
            return s;
        },
        std::plus<>());
}

std::vector<Index> NeighbourLists::counts() const {
    if (!compact()) return count;
    std::vector<Index> c(rows());
    for (std::size_t i = 0; i < c.size(); ++i) c[i] = size_of(Index(i));
    return c;
}

namespace {

/// dst[0, n) = src[0, n) in whole chunks of 16 elements (fixed-size copies the compiler inlines
/// as vector moves, where a library call per range costs more than the copy for the ~20-element
/// ranges of a cell neighbourhood). Reads and writes up to 15 elements past n: the grid's arrays
/// carry kPadding readable entries after the last slot, and the cache's arrays as many after
/// its count.
template <class T>
void copy_chunks(T* dst, const T* src, std::size_t n) {
    static_assert(UniformGrid::kPadding >= 16);
    for (std::size_t s = 0; s < n; s += 16) std::memcpy(dst + s, src + s, 16 * sizeof(T));
}

}  // namespace

void CandidateCache::fill(const UniformGrid& grid, std::span<const Vec3> positions, const Vec3& at,
                          std::int64_t at_cell) {
    const CandidateRanges ranges = grid.candidate_ranges(at);
    cell = at_cell;
    count = ranges.total;
    const std::size_t size = count + UniformGrid::kPadding;
    for (auto* axis : {&x, &y, &z})
        if (axis->size() < size) axis->resize(size);
    if (index.size() < size) index.resize(size);
    const Index* sorted_index = grid.sorted_index().data();
    const bool copy = grid.sorted_x() != nullptr;
    std::size_t k = 0;
    for (int r = 0; r < ranges.count; ++r) {
        const std::size_t b = ranges.begin[r], n = ranges.end[r] - ranges.begin[r];
        copy_chunks(index.data() + k, sorted_index + b, n);
        if (copy) {  // the grid's own coordinates, contiguous by slot
            copy_chunks(x.data() + k, grid.sorted_x() + b, n);
            copy_chunks(y.data() + k, grid.sorted_y() + b, n);
            copy_chunks(z.data() + k, grid.sorted_z() + b, n);
        } else {
            for (std::size_t s = 0; s < n; ++s) {
                const Vec3& p = positions[sorted_index[b + s]];
                x[k + s] = p.x();
                y[k + s] = p.y();
                z[k + s] = p.z();
            }
        }
        k += n;
    }
    // The padding after the candidates: far points (never in range) and a valid index; written
    // last, since the chunked copies run into it.
    for (auto* axis : {&x, &y, &z})
        std::fill(axis->begin() + std::ptrdiff_t(count), axis->begin() + std::ptrdiff_t(size),
                  std::numeric_limits<Real>::max());
    std::fill(index.begin() + std::ptrdiff_t(count), index.begin() + std::ptrdiff_t(size), Index(0));
}

namespace {

constexpr Index kNoSelf = ~Index(0);

/// Writes the candidates within r2 of xi (j != self) to dst; returns their count. Branch-free:
/// every candidate is written and the cursor advances only when it is in range (the in-range
/// test is a coin toss for about half the candidates once the start lattice has become
/// disordered, and a branch mispredicts on it).
Index filter_scalar(const CandidateCache& cache, const Vec3& xi, Index self, Real r2, Index* dst) {
    Index c = 0;
    for (std::size_t k = 0; k < cache.count; ++k) {
        const Index j = cache.index[k];
        dst[c] = j;
        c += Index((xi - Vec3(cache.x[k], cache.y[k], cache.z[k])).squaredNorm() < r2) & Index(j != self);
    }
    return c;
}

/// The list of query xi from the candidates of its cell (cache_for has filled `cache`).
Index filter(const CandidateCache& cache, const Vec3& xi, Index self, Real r2, Index* dst, bool simd) {
    if (cache.count == 0) return 0;
    return simd ? filter_candidates_simd(cache, xi, self, r2, dst) : filter_scalar(cache, xi, self, r2, dst);
}

/// The scalar form of filter_ranges_simd: the candidates of `ranges` read from the grid's
/// slot-ordered coordinates, branch-free as filter_scalar.
Index filter_ranges_scalar(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, Real r2,
                           Index* dst) {
    const Real *sx = grid.sorted_x(), *sy = grid.sorted_y(), *sz = grid.sorted_z();
    const Index* sj = grid.sorted_index().data();
    Index c = 0;
    for (int r = 0; r < ranges.count; ++r)
        for (std::size_t k = ranges.begin[r]; k < ranges.end[r]; ++k) {
            const Index j = sj[k];
            dst[c] = j;
            c += Index((xi - Vec3(sx[k], sy[k], sz[k])).squaredNorm() < r2) & Index(j != self);
        }
    return c;
}

/// Where one query's candidates are read from: its cell's cache, the grid's slot-ordered
/// coordinates directly (`direct`, the 9 ranges in `ranges`), or a drifted grid's wider reach
/// (`drifted`, the ranges in the worker's DriftScratch).
struct QuerySource {
    bool direct = false, drifted = false;
    CandidateRanges ranges;
    std::size_t count = 0;  ///< candidates
};

/// What one worker keeps for the queries of a drifted grid (filter_drifted).
struct DriftScratch {
    UniformGrid::WideRanges ranges;  ///< the current query's reach
    CandidateCache current;          ///< its candidates at their current positions
    std::vector<std::uint64_t> keys;
};

/// Picks the source of query xi. A cache fill copies every candidate once, as much as one filter
/// pass: it pays when the cache already holds the query's cell or the next query (`next_cell`,
/// -1 for none) shares it. Otherwise the query reads the grid's own coordinates (grids that
/// keep them; the lists are the same, in the same order): a subset build (binned and individual
/// stepping) whose due particles are scattered meets most cells once, and so does a build of
/// every list on a disordered flow, where a cell holds two or three particles.
/// `cell` is the query's own (grid.cell_of(xi)); `reach` is the list radius plus the grid's drift.
QuerySource source_for(const UniformGrid& grid, std::span<const Vec3> grid_positions, CandidateCache& cache,
                       DriftScratch& drift, const Vec3& xi, std::int64_t cell, std::int64_t next_cell, Real reach) {
    QuerySource q;
    if (grid.drift() > 0) {
        q.drifted = true;
        drift.ranges = grid.ranges_within(xi, reach);
        q.count = drift.ranges.total;
        return q;
    }
    if (cell != cache.cell && next_cell != cell && grid.sorted_x() != nullptr) {
        q.direct = true;
        q.ranges = grid.candidate_ranges(xi);
        q.count = q.ranges.total;
        return q;
    }
    if (cell != cache.cell) cache.fill(grid, grid_positions, xi, cell);
    q.count = cache.count;
    return q;
}

/// The list of query xi against a drifted grid, equal to a fresh grid's (the same entries in
/// the same order): (1) the candidates within reach (radius + drift) at the build's coordinates,
/// a superset of those in range now; (2) those at their current positions through the filter a
/// fresh grid's query uses (the same arithmetic, so the same borderline decisions); (3) sorted
/// by current cell and index, a fresh grid's order.
Index filter_drifted(const UniformGrid& grid, std::span<const Vec3> positions, const Vec3& xi, Index self, Real r2,
                     Real reach2, Index* dst, bool simd, DriftScratch& s) {
    if (s.ranges.total == 0) return 0;
    Index m = 0;
    for (const CandidateRanges& ranges : s.ranges.part) {
        if (ranges.count == 0) continue;
        if (grid.sorted_x() != nullptr) {
            m += simd ? filter_ranges_simd(grid, ranges, xi, self, reach2, dst + m)
                      : filter_ranges_scalar(grid, ranges, xi, self, reach2, dst + m);
        } else {
            const Index* sj = grid.sorted_index().data();
            for (int r = 0; r < ranges.count; ++r)
                for (Index k = ranges.begin[r]; k < ranges.end[r]; ++k) dst[m++] = sj[k];
        }
    }
    CandidateCache& c = s.current;
    const std::size_t size = m + UniformGrid::kPadding;
    for (auto* axis : {&c.x, &c.y, &c.z})
        if (axis->size() < size) axis->resize(size);
    if (c.index.size() < size) c.index.resize(size);
    for (Index k = 0; k < m; ++k) {
        const Vec3& p = positions[dst[k]];
        c.x[k] = p.x();
        c.y[k] = p.y();
        c.z[k] = p.z();
        c.index[k] = dst[k];
    }
    for (std::size_t k = m; k < size; ++k) {
        c.x[k] = c.y[k] = c.z[k] = std::numeric_limits<Real>::max();
        c.index[k] = 0;
    }
    c.count = m;
    c.cell = -1;
    const Index found = filter(c, xi, self, r2, dst, simd);
    // A fresh grid offers only the 27 cells around the query's (a pair just under r apart along
    // an axis can lie two cells apart, the cell size being rounded): the same cells here.
    if (s.keys.size() < found) s.keys.resize(found);
    const Eigen::Vector3i cq = grid.cell_coords(xi);
    Index n = 0;
    for (Index k = 0; k < found; ++k) {
        const Eigen::Vector3i cj = grid.cell_coords(positions[dst[k]]);
        if ((cj - cq).cwiseAbs().maxCoeff() <= 1) s.keys[n++] = cell_key(grid.cell_index(cj), dst[k]);
    }
    insertion_sort(s.keys.data(), n);
    for (Index k = 0; k < n; ++k) dst[k] = Index(s.keys[k]);
    return n;
}

/// The list of query xi from the source source_for picked.
Index filter(const UniformGrid& grid, std::span<const Vec3> grid_positions, const CandidateCache& cache,
             const QuerySource& q, const Vec3& xi, Index self, Real r2, Real reach2, Index* dst, bool simd,
             DriftScratch& drift) {
    if (q.drifted) return filter_drifted(grid, grid_positions, xi, self, r2, reach2, dst, simd, drift);
    if (!q.direct) return filter(cache, xi, self, r2, dst, simd);
    if (q.count == 0) return 0;
    return simd ? filter_ranges_simd(grid, q.ranges, xi, self, r2, dst) : filter_ranges_scalar(grid, q.ranges, xi, self, r2, dst);
}

/// Every list (or the subset's), back to back per block of query particles, written straight
/// into the block (no copy): a block grows when its next query's candidates might not fit.
/// A subset build rewrites the ends of every row in the blocks it touches and empties the blocks
/// of the last subset: O(kBlock) per block touched, not O(n).
void build_compact(const UniformGrid& grid, std::span<const Vec3> grid_positions,
                   std::span<const Vec3> query_positions, Real r2, bool exclude_self,
                   const QuerySubset& subset, NeighbourLists& lists, bool simd) {
    const std::size_t n = query_positions.size();
    constexpr std::size_t B = NeighbourLists::kBlock;
    // A subset of n rows is every row (it is ascending and unique): built as every list, with
    // `queried` kept as a subset build keeps it (binned stepping's steps with every row due).
    const bool full_subset = !subset.all && subset.indices.size() == n;
    const bool every = subset.all || full_subset;
    if (lists.capacity != 0 || lists.end.size() != n) {  // from the slab layout or another size
        lists.capacity = 0;
        std::vector<Index>().swap(lists.indices);
        std::vector<Index>().swap(lists.count);
        lists.end.assign(n, 0);
        lists.queried.clear();
    }
    lists.blocks.resize((n + B - 1) / B);
    // The last subset's blocks hold the only other non-empty lists: empty them (this build
    // rewrites the blocks it touches).
    if (!every && lists.queried.size() == n)  // the last build was every row's
        std::fill(lists.end.begin(), lists.end.end(), Index(0));
    else if (!every)
        for (std::size_t k = 0; k < lists.queried.size(); ++k) {
            const std::size_t b = lists.queried[k] / B;
            if (k > 0 && lists.queried[k - 1] / B == b) continue;
            std::fill(lists.end.begin() + std::ptrdiff_t(b * B), lists.end.begin() + std::ptrdiff_t(std::min(n, (b + 1) * B)),
                      Index(0));
        }
    // The query rows by block: [first[k], first[k + 1]) of `rows` fall in one block.
    const std::span<const Index> rows = subset.indices;
    std::vector<std::size_t> first;
    if (!every)
        for (std::size_t k = 0; k < rows.size(); ++k)
            if (k == 0 || rows[k] / B != rows[k - 1] / B) first.push_back(k);
    first.push_back(rows.size());
    const std::size_t jobs = every ? lists.blocks.size() : first.size() - 1;
    tbb::enumerable_thread_specific<CandidateCache> caches;
    tbb::enumerable_thread_specific<DriftScratch> drifts;
    const Real reach = std::sqrt(r2) + grid.drift(), reach2 = reach * reach;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, jobs, 1), [&](const auto& r) {
        CandidateCache& cache = caches.local();
        DriftScratch& drift = drifts.local();
        for (std::size_t job = r.begin(); job < r.end(); ++job) {
            const std::size_t b = every ? job : rows[first[job]] / B;
            const std::size_t row_end = std::min(n, (b + 1) * B);
            std::size_t k = every ? 0 : first[job];  // the next subset row
            const std::size_t k_end = every ? 0 : first[job + 1];
            std::vector<Index>& buf = lists.blocks[b];
            std::size_t used = 0, peak = NeighbourLists::kSlack;
            std::int64_t known = -1;  // the next query's cell when it was looked ahead (-1: not)
            for (std::size_t i = b * B; i < row_end; ++i) {
                if (!every && !(k < k_end && rows[k] == i)) {  // not queried: empty
                    lists.end[i] = Index(used);
                    continue;
                }
                ++k;
                const Vec3 xi = query_positions[i];
                // Each query's cell is computed once: the look-ahead's is kept for the next.
                const std::int64_t cell = known >= 0 ? known : grid.cell_of(xi);
                if (grid.empty_around(cell)) {  // no candidate: one lookup
                    known = -1;
                    lists.end[i] = Index(used);
                    continue;
                }
                const std::int64_t next_cell = every ? (i + 1 < row_end ? grid.cell_of(query_positions[i + 1]) : -1)
                                               : (k < k_end ? grid.cell_of(query_positions[rows[k]]) : -1);
                known = next_cell;
                const QuerySource src = source_for(grid, grid_positions, cache, drift, xi, cell, next_cell, reach);
                // Room for every candidate plus a vector of slack (the vectorised filter's
                // whole-vector stores, and the readers' whole-vector loads).
                const std::size_t need = used + src.count + NeighbourLists::kSlack;
                peak = std::max(peak, need);
                if (buf.size() < need) {  // grows by a 32nd over the need: a block's lists change little per step
                    std::vector<Index> grown(need + need / 32);
                    std::copy_n(buf.data(), used, grown.data());
                    buf.swap(grown);
                }
                used += filter(grid, grid_positions, cache, src, xi, exclude_self ? Index(i) : kNoSelf, r2, reach2,
                               buf.data() + used, simd, drift);
                lists.end[i] = Index(used);
            }
            // A block holding more than a 16th above what this build needed at its peak gives
            // the rest back, keeping a 32nd (lists thin out as a flow spreads from its start).
            if (every && buf.size() > peak + peak / 16) {
                std::vector<Index> trimmed(std::max(peak + peak / 32, used + NeighbourLists::kSlack));
                std::copy_n(buf.data(), used, trimmed.data());
                buf.swap(trimmed);
            }
        }
    });
    if (subset.all)
        lists.queried.clear();
    else
        lists.queried.assign(rows.begin(), rows.end());
}

/// The lists of the subset, each in its fixed slot of `capacity` entries.
void build_slab(const UniformGrid& grid, std::span<const Vec3> grid_positions,
                std::span<const Vec3> query_positions, Real r2, bool exclude_self,
                const QuerySubset& subset, NeighbourLists& lists, bool simd) {
    const std::size_t n = query_positions.size();
    if (lists.capacity == 0) {  // first build, or from the compact layout (whose lists are kept)
        std::vector<Index> counts = lists.counts();
        Index longest = 0;
        for (Index c : counts) longest = std::max(longest, c);
        const Index cap = std::max<Index>(48, (longest + 15) / 16 * 16);
        if (counts.size() == n) {
            std::vector<Index> slab(n * std::size_t(cap));
            for (std::size_t i = 0; i < n; ++i) {
                const auto l = lists.of(Index(i));
                std::copy(l.begin(), l.end(), slab.data() + i * cap);
            }
            lists.indices.swap(slab);
            lists.count.swap(counts);
        }
        lists.capacity = cap;
        lists.queried.clear();
        std::vector<Index>().swap(lists.end);
        std::vector<std::vector<Index>>().swap(lists.blocks);
    }
    if (lists.count.size() != n) lists.count.assign(n, 0);
    const std::size_t m = subset.all ? n : subset.indices.size();
    for (;;) {
        if (lists.indices.size() != n * std::size_t(lists.capacity))
            lists.indices.resize(n * std::size_t(lists.capacity));
        std::atomic<Index> overflow{0};
        const Index cap = lists.capacity;
        tbb::enumerable_thread_specific<std::vector<Index>> scratch;
        tbb::enumerable_thread_specific<CandidateCache> caches;
        tbb::enumerable_thread_specific<DriftScratch> drifts;
        const Real reach = std::sqrt(r2) + grid.drift(), reach2 = reach * reach;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 256), [&](const auto& r) {
            Index local_max = 0;
            std::vector<Index>& found = scratch.local();
            CandidateCache& cache = caches.local();
            DriftScratch& drift = drifts.local();
            std::int64_t known = -1;  // the next query's cell when it was looked ahead (-1: not)
            for (std::size_t q = r.begin(); q < r.end(); ++q) {
                const Index i = subset.all ? Index(q) : subset.indices[q];
                const Vec3 xi = query_positions[i];
                const std::int64_t cell = known >= 0 ? known : grid.cell_of(xi);
                if (grid.empty_around(cell)) {  // no candidate: one lookup
                    known = -1;
                    lists.count[i] = 0;
                    continue;
                }
                const std::int64_t next_cell =
                    q + 1 < r.end() ? grid.cell_of(query_positions[subset.all ? Index(q + 1) : subset.indices[q + 1]]) : -1;
                known = next_cell;
                const QuerySource src = source_for(grid, grid_positions, cache, drift, xi, cell, next_cell, reach);
                if (found.size() < src.count + NeighbourLists::kSlack) found.resize(2 * src.count + NeighbourLists::kSlack);
                const Index c = filter(grid, grid_positions, cache, src, xi, exclude_self ? i : kNoSelf, r2, reach2,
                                       found.data(), simd, drift);
                std::copy_n(found.data(), std::min(c, cap), lists.indices.data() + std::size_t(i) * cap);
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
            build_slab(grid, grid_positions, query_positions, r2, exclude_self, QuerySubset{}, lists, simd);
            return;
        }
    }
}

}  // namespace

void build_neighbour_lists(const UniformGrid& grid, std::span<const Vec3> grid_positions,
                           std::span<const Vec3> query_positions, Real radius, bool exclude_self,
                           const QuerySubset& subset, NeighbourLists& lists, bool simd) {
    if (grid_positions.size() < grid.particle_count())
        throw std::logic_error("build_neighbour_lists: the grid holds more particles than the positions given");
    const Real r2 = radius * radius;
    if (subset.all || !subset.keep_others)
        build_compact(grid, grid_positions, query_positions, r2, exclude_self, subset, lists, simd);
    else
        build_slab(grid, grid_positions, query_positions, r2, exclude_self, subset, lists, simd);
}

void NeighbourLists::permute(std::span<const Index> perm, bool remap_entries) {
    const std::size_t n = rows();
    if (n == 0 || perm.size() != n) return;
    std::vector<Index> inverse;
    if (remap_entries || !queried.empty()) {
        inverse.resize(n);
        for (std::size_t i = 0; i < n; ++i) inverse[perm[i]] = Index(i);
    }
    for (Index& i : queried) i = inverse[i];
    std::sort(queried.begin(), queried.end());
    auto copy_list = [&](Index from, Index* dst) {
        const auto src = of(from);
        for (std::size_t k = 0; k < src.size(); ++k) dst[k] = remap_entries ? inverse[src[k]] : src[k];
    };
    if (!compact()) {
        std::vector<Index> new_count(n);
        std::vector<Index> new_indices(indices.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                new_count[i] = count[perm[i]];
                copy_list(perm[i], new_indices.data() + i * capacity);
            }
        });
        count.swap(new_count);
        indices.swap(new_indices);
        return;
    }
    std::vector<Index> new_end(n);
    std::vector<std::vector<Index>> new_blocks(blocks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            const std::size_t last = std::min(n, (b + 1) * kBlock);
            std::size_t used = 0;
            for (std::size_t i = b * kBlock; i < last; ++i) used += size_of(perm[i]);
            new_blocks[b].resize(used + kSlack);
            used = 0;
            for (std::size_t i = b * kBlock; i < last; ++i) {
                copy_list(perm[i], new_blocks[b].data() + used);
                used += size_of(perm[i]);
                new_end[i] = Index(used);
            }
        }
    });
    end.swap(new_end);
    blocks.swap(new_blocks);
}

std::vector<Index> NeighbourLists::concatenated() const {
    std::vector<Index> out;
    out.reserve(total());
    for (std::size_t i = 0; i < rows(); ++i) {
        const auto l = of(Index(i));
        out.insert(out.end(), l.begin(), l.end());
    }
    return out;
}

void NeighbourLists::assign_compact(std::span<const Index> counts, std::span<const Index> entries) {
    capacity = 0;
    std::vector<Index>().swap(indices);
    std::vector<Index>().swap(count);
    const std::size_t n = counts.size();
    end.assign(n, 0);
    blocks.assign((n + kBlock - 1) / kBlock, {});
    std::size_t from = 0;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
        std::size_t used = 0;
        const std::size_t last = std::min(n, (b + 1) * kBlock);
        for (std::size_t i = b * kBlock; i < last; ++i) used += counts[i];
        if (from + used > entries.size()) throw std::length_error("neighbour lists: fewer entries than the counts sum to");
        blocks[b].assign(entries.begin() + std::ptrdiff_t(from), entries.begin() + std::ptrdiff_t(from + used));
        blocks[b].resize(used + kSlack);
        used = 0;
        for (std::size_t i = b * kBlock; i < last; ++i) used += counts[i], end[i] = Index(used);
        from += used;
    }
    queried.clear();
    for (std::size_t i = 0; i < n; ++i)
        if (counts[i] > 0) queried.push_back(Index(i));
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
    auto morton = [](const Eigen::Vector3i& c) {
        return spread_bits(std::uint64_t(c[0])) | spread_bits(std::uint64_t(c[1])) << 1 |
               spread_bits(std::uint64_t(c[2])) << 2;
    };
    std::vector<std::uint64_t> key(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) key[i] = morton(grid.cell_coords(positions[i]));
    });
    // A stable LSD radix sort over the bits the grid's codes use (18 for a 64^3 grid: two passes
    // of 11-bit digits), so ties keep index order: the order of sorting (key, index) pairs, in
    // O(n) per pass.
    const int bits = std::bit_width(morton(grid.dims() - Eigen::Vector3i::Ones()));
    constexpr int kDigit = 11;
    constexpr std::size_t kBuckets = std::size_t(1) << kDigit;
    std::vector<Index> perm(n), next(n);
    std::vector<std::uint64_t> next_key(n);
    for (std::size_t i = 0; i < n; ++i) perm[i] = Index(i);
    std::vector<std::size_t> start(kBuckets);
    for (int shift = 0; shift < bits; shift += kDigit) {  // keys move with their indices
        std::fill(start.begin(), start.end(), 0);
        for (std::size_t k = 0; k < n; ++k) ++start[(key[k] >> shift) & (kBuckets - 1)];
        std::size_t sum = 0;
        for (std::size_t& s : start) sum += std::exchange(s, sum);
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t to = start[(key[k] >> shift) & (kBuckets - 1)]++;
            next[to] = perm[k];
            next_key[to] = key[k];
        }
        perm.swap(next);
        key.swap(next_key);
    }
    return perm;
}

}  // namespace sph
