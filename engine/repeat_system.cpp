#include "engine/repeat_system.hpp"

#include <algorithm>
#include <stdexcept>

namespace sph {

RepeatSystem::RepeatSystem(std::string name, std::vector<std::unique_ptr<System>> body,
                           std::function<bool(const World&, int)> more, std::function<void(World&, int)> done)
    : m_name(std::move(name)), m_body(std::move(body)), m_more(std::move(more)), m_done(std::move(done)) {
    auto add = [](std::vector<std::string>& v, const std::string& r) {
        if (std::find(v.begin(), v.end(), r) == v.end()) v.push_back(r);
    };
    for (const auto& s : m_body)
        for (const auto& w : s->access().writes) add(m_access.writes, w);
    for (const auto& s : m_body)
        for (const auto& r : s->access().reads)
            if (std::find(m_access.writes.begin(), m_access.writes.end(), r) == m_access.writes.end())
                add(m_access.reads, r);
    // A resource the body both reads and writes is read by the loop too (pass k reads pass k-1).
    for (const auto& s : m_body)
        for (const auto& r : s->access().reads)
            if (std::find(m_access.writes.begin(), m_access.writes.end(), r) != m_access.writes.end())
                add(m_access.reads, r);
}

void RepeatSystem::register_components(World& w) {
    if (m_graph) return;
    for (auto& s : m_body) s->register_components(w);
    m_graph = std::make_unique<SystemGraph>(std::move(m_body), w);
}

void RepeatSystem::run(World& w) {
    if (!m_graph) throw std::logic_error("RepeatSystem '" + m_name + "' run before register_components");
    int k = 0;
    do {
        m_graph->run();
        ++k;
    } while (m_more(w, k));
    if (m_done) m_done(w, k);
}

}  // namespace sph
