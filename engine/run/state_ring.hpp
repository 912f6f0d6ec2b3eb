#pragma once
/// @file state_ring.hpp
/// @brief A ring of the last few simulation states for a rollback (a recipe asks for its depth). A state is every column of the fluid and boundary stores, copied column by
/// column, the clock and every Kept resource (resources.hpp), copied generically.
/// Slots are reused, so saving allocates only while the ring fills or a set grows.
#include <cstddef>
#include <vector>

#include "engine/data/world.hpp"

namespace sph {

class StateRing {
public:
    /// @param depth states kept (the rollback reaches at most `depth` steps back).
    explicit StateRing(std::size_t depth) : m_slots(depth) {}

    /// @brief Saves the world's state as the newest entry (dropping the oldest when full).
    void save(const World& w);
    /// @brief States it can hold.
    std::size_t depth() const { return m_slots.size(); }
    /// @brief Number of states held.
    std::size_t size() const { return m_count; }
    /// @brief Drops every state (the world was replaced, e.g. by a checkpoint's).
    void clear() { m_count = m_next = 0; }
    /// @brief Restores the state saved `back` saves ago (1: the newest), or the oldest held if
    /// fewer are held, and drops the states newer than it. Returns how many saves back it went
    /// (0 when the ring is empty and nothing was restored).
    std::size_t restore(World& w, std::size_t back);

    /// One saved state.
    struct State {
        ComponentStore::Snapshot fluid, boundary;
        Clock clock;
        ResourceStore::Snapshot resources;
    };
    /// @brief The states held, oldest first (a checkpoint writes them).
    std::vector<const State*> held() const;
    /// @brief Saves `w` as the newest entry and returns it: a checkpoint's state overwrites it
    /// (its columns and resources then have the types this world's recipe uses).
    State& push(const World& w);

private:
    std::vector<State> m_slots;
    std::size_t m_next = 0;   ///< slot the next save writes
    std::size_t m_count = 0;  ///< states held
};

}  // namespace sph
