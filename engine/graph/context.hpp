#pragma once
/// @file context.hpp
/// @brief What a system gets when it runs: the parts of the World its Access declares, by typed
/// handle, and nothing else. read() hands out const views of what is declared read or written,
/// write() mutable views of what is declared written; anything else throws AccessError naming
/// the system and the key. The check is a short scan of the declaration (a few per run of a
/// system, never per particle), so it is on in every build.
#include <span>
#include <stdexcept>
#include <string>

#include "engine/core/access.hpp"
#include "engine/data/world.hpp"

namespace sph {

/// @brief A system touched something its Access does not declare (a programming error).
class AccessError : public std::logic_error {
public:
    using std::logic_error::logic_error;
};

class Context {
public:
    /// @param access must outlive the context (the graph keeps each system's declaration).
    Context(World& world, std::string system, const Access& access)
        : m_world(world), m_system(std::move(system)), m_access(access) {}

    template <class T>
    std::span<const T> read(const ColumnRef<T>& c) const {
        require(m_access.may_read(key_of(c)), "read", key_of(c));
        return std::as_const(m_world.store(c.set)).get(c.component);
    }
    template <class T>
    std::span<T> write(const ColumnRef<T>& c) const {
        require(m_access.may_write(key_of(c)), "write", key_of(c));
        return m_world.store(c.set).get(c.component);
    }
    template <class T>
    const T& read(const Resource<T>& r) const {
        require(m_access.may_read(key_of(r)), "read", key_of(r));
        return resolve(r);
    }
    template <class T>
    T& write(const Resource<T>& r) const {
        require(m_access.may_write(key_of(r)), "write", key_of(r));
        return resolve(r);
    }
    std::uint64_t read(const Counter& c) const {
        require(m_access.may_read(key_of(c)), "read", key_of(c));
        return m_world.counter_value(c.name);
    }
    /// @brief The counter to set this step (declared with write(counter::...)).
    std::uint64_t& write(const Counter& c) const {
        require(m_access.may_write(key_of(c)), "write", key_of(c));
        // Counters are created before any system runs (SystemGraph, run_system), so concurrent
        // systems only look them up and never insert into the map.
        const auto it = m_world.counters.find(c.name);
        if (it == m_world.counters.end())
            throw AccessError("counter '" + std::string(c.name) + "' of system '" + m_system +
                              "' was not created before the system ran");
        return it->second;
    }

    /// @brief Changes a set's size (every column; new rows zero). Declared with Access::resizes.
    void resize(SetId set, std::size_t n) const {
        require(m_access.resizes_set(set), "resize", std::string(set_name(set)));
        m_world.store(set).resize(n);
    }

    // Constant for the whole step: read without a declaration.
    const Physics& physics() const { return m_world.physics; }
    const CubicSpline& kernel() const { return m_world.kernel; }
    const Aabb& domain() const { return m_world.domain; }
    const Clock& clock() const { return m_world.clock; }
    /// @brief Particles in a set. Stable while the step runs except for a system that resizes
    /// the set, which the graph orders against every other user of it.
    std::size_t size(SetId set) const { return m_world.store(set).size(); }
    /// @brief The set's row layout generation (ComponentStore::layout): a system that keeps row
    /// indices from one step to the next rebuilds them when it changes.
    std::uint64_t layout(SetId set) const { return m_world.store(set).layout(); }
    /// @brief The set's membership generation (ComponentStore::membership).
    std::uint64_t membership(SetId set) const { return m_world.store(set).membership(); }
    /// @brief Whether a column is allocated (optional columns of a set).
    bool has(SetId set, std::string_view component) const { return m_world.store(set).has(component); }

    const std::string& system() const { return m_system; }
    const Access& access() const { return m_access; }

private:
    template <class T>
    T& resolve(const Resource<T>& r) const {
        if (r.member) return m_world.*(r.member);
        return m_world.resources.get<T>(r.name);
    }
    void require(bool declared, const char* how, const std::string& key) const {
        if (!declared)
            throw AccessError("system '" + m_system + "' tried to " + how + " '" + key +
                              "', which its access declaration does not " +
                              (std::string(how) == "read" ? "read or write" : how));
    }

    World& m_world;
    std::string m_system;
    const Access& m_access;
};

}  // namespace sph
