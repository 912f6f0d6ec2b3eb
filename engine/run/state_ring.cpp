#include "engine/run/state_ring.hpp"

#include <algorithm>

namespace sph {

void StateRing::save(const World& w) {
    if (!m_slots.empty()) push(w);
}

StateRing::State& StateRing::push(const World& w) {
    State& s = m_slots[m_next];
    w.fluid.store.save(s.fluid);
    w.boundary.store.save(s.boundary);
    s.clock = w.clock;
    w.resources.save(s.resources);
    m_next = (m_next + 1) % m_slots.size();
    m_count = std::min(m_count + 1, m_slots.size());
    return s;
}

std::vector<const StateRing::State*> StateRing::held() const {
    std::vector<const State*> out;
    const std::size_t n = m_slots.size();
    for (std::size_t k = m_count; k > 0; --k) out.push_back(&m_slots[(m_next + n - k) % n]);
    return out;
}

std::size_t StateRing::restore(World& w, std::size_t back) {
    if (m_count == 0 || back == 0) return 0;
    back = std::min(back, m_count);
    const std::size_t n = m_slots.size();
    const std::size_t index = (m_next + n - back) % n;
    const State& s = m_slots[index];
    w.fluid.store.restore(s.fluid);
    w.boundary.store.restore(s.boundary);
    w.clock = s.clock;
    w.resources.restore(s.resources);
    // The restored state is where the run resumes: the next step saves it again into the
    // same slot, so it and every newer state are dropped here.
    m_next = index;
    m_count -= back;
    return back;
}

}  // namespace sph
