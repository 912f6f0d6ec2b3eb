#pragma once
/// @file access.hpp
/// @brief Typed handles for everything a system may touch, and the declaration a system makes
/// of them. The graph builder derives the flow-graph edges from the declarations; the
/// per-system Context (context.hpp) hands out only what was declared.
///
/// Three kinds of handle, each keyed by a name that is unique across kinds:
///   ColumnRef<T>  a column of a particle set:      fluid(comp::density)   -> "fluid.density"
///   Resource<T>   any other shared data of a step: res::fluid_neighbours  -> "fluid.neighbours"
///   Counter       a per-step statistic (stats.csv): counter::active       -> "counter.active"
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/component_store.hpp"

namespace sph {

struct World;

/// @brief The two particle sets.
enum class SetId : std::uint8_t { Fluid, Boundary };
constexpr std::string_view set_name(SetId s) { return s == SetId::Fluid ? "fluid" : "boundary"; }

/// @brief A column of one particle set.
template <class T>
struct ColumnRef {
    SetId set;
    Component<T> component;
    using value_type = T;
};
template <class T>
constexpr ColumnRef<T> fluid(Component<T> c) { return {SetId::Fluid, c}; }
template <class T>
constexpr ColumnRef<T> boundary(Component<T> c) { return {SetId::Boundary, c}; }

/// @brief Shared non-column data. `member` points into World for the engine's own resources
/// (grids, neighbour lists, the step size); it is null for a resource a system owns, which
/// lives in World::resources under `name` (see resources.hpp).
template <class T>
struct Resource {
    std::string_view name;
    T World::*member = nullptr;
    using value_type = T;
};

/// @brief A per-step work counter or statistic, written by the system that declares it and
/// recorded as a stats.csv column of the same name.
struct Counter {
    std::string_view name;
};

/// @brief The key a handle is known by in declarations and graph pictures.
template <class T>
std::string key_of(const ColumnRef<T>& c) {
    return std::string(set_name(c.set)) + "." + std::string(c.component.name);
}
template <class T>
std::string key_of(const Resource<T>& r) {
    return std::string(r.name);
}
inline std::string key_of(const Counter& c) { return "counter." + std::string(c.name); }

/// @brief What a system reads and writes, built from typed handles:
///   Access().read(fluid(comp::position), res::fluid_neighbours).write(fluid(comp::density))
/// A write implies a read. `resizes(set)` declares that the system changes the set's size
/// (inserting particles), which reallocates every column of it: the graph orders it against every
/// system that touches the set.
class Access {
public:
    template <class... H>
    Access& read(const H&... handles) {
        (add(m_reads, key_of(handles)), ...);
        return *this;
    }
    template <class... H>
    Access& write(const H&... handles) {
        (add(m_writes, key_of(handles)), ...);
        return *this;
    }
    /// @brief Writes that store exact copies of columns the engine checked when they were written
    /// (a base state saved from the current state): ordered like any write, but the finiteness
    /// trace (Simulation::trace_non_finite) does not read them again.
    template <class... H>
    Access& copies(const H&... handles) {
        write(handles...);
        (add(m_copies, key_of(handles)), ...);
        return *this;
    }
    /// @brief Reads (r) and writes (w) only when `when` holds: optional parts of a system.
    template <class... H>
    Access& read_if(bool when, const H&... handles) {
        if (when) read(handles...);
        return *this;
    }
    template <class... H>
    Access& write_if(bool when, const H&... handles) {
        if (when) write(handles...);
        return *this;
    }
    Access& resizes(SetId set) {
        if (std::find(m_resizes.begin(), m_resizes.end(), set) == m_resizes.end()) m_resizes.push_back(set);
        return *this;
    }
    /// @brief Declares that the system writes its particle columns only at the rows listed in
    /// this index resource (the active set), each row at most once: the engine's finiteness
    /// check then reads those rows only, so its cost follows the work.
    template <class T>
    Access& rows(const Resource<T>& r) {
        m_rows = key_of(r);
        return *this;
    }
    /// @brief The index resource named by rows(), or empty (every row may be written).
    const std::string& written_rows() const { return m_rows; }
    /// @brief Adds everything another declaration holds (a loop's body towards its parent).
    Access& merge(const Access& other);

    const std::vector<std::string>& reads() const { return m_reads; }
    const std::vector<std::string>& writes() const { return m_writes; }
    const std::vector<SetId>& resized_sets() const { return m_resizes; }
    bool resizes_set(SetId set) const {
        return std::find(m_resizes.begin(), m_resizes.end(), set) != m_resizes.end();
    }
    bool may_read(std::string_view key) const { return contains(m_reads, key) || contains(m_writes, key); }
    bool may_write(std::string_view key) const { return contains(m_writes, key); }
    /// @brief Whether every write of this key is a copy (copies()).
    bool is_copy(std::string_view key) const { return contains(m_copies, key); }
    /// @brief The counters among the writes (their names without "counter.").
    std::vector<std::string> counters() const;

private:
    static void add(std::vector<std::string>& v, std::string key) {
        if (std::find(v.begin(), v.end(), key) == v.end()) v.push_back(std::move(key));
    }
    static bool contains(const std::vector<std::string>& v, std::string_view key) {
        return std::find(v.begin(), v.end(), key) != v.end();
    }
    std::vector<std::string> m_reads, m_writes, m_copies;
    std::vector<SetId> m_resizes;
    std::string m_rows;
};

}  // namespace sph
