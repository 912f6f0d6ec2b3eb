#include "engine/graph/repeat_system.hpp"

#include <algorithm>
#include <stdexcept>

#include "engine/graph/context.hpp"

namespace sph {

RepeatSystem::RepeatSystem(std::string name, std::vector<std::unique_ptr<System>> body,
                           std::function<bool(const Context&, int)> more, std::function<void(Context&, int)> done,
                           Access extra)
    : m_name(std::move(name)), m_body(std::move(body)), m_more(std::move(more)), m_done(std::move(done)) {
    // The union of the body's declarations: a resource the body writes is also read by the
    // loop (pass k reads pass k-1), which Access::write already implies.
    for (const auto& s : m_body) m_access.merge(s->access());
    m_access.merge(extra);
}

void RepeatSystem::register_components(World& w) {
    if (m_graph) return;
    for (auto& s : m_body) s->register_components(w);
    m_graph = std::make_unique<SystemGraph>(std::move(m_body), w);
}

void RepeatSystem::run(Context& ctx) {
    if (!m_graph) throw std::logic_error("RepeatSystem '" + m_name + "' run before register_components");
    int k = 0;
    do {
        m_graph->run();
        ++k;
    } while (m_more(ctx, k));
    if (m_done) m_done(ctx, k);
}

}  // namespace sph
