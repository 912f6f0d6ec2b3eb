#include "engine/graph/system_graph.hpp"

#include <tbb/flow_graph.h>

#include <algorithm>
#include <exception>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "engine/graph/context.hpp"

namespace sph {

std::vector<Edge> derive_edges(const std::vector<Access>& declared) {
    // A system that resizes a set reallocates every column of it, so it writes the set's size
    // and every access to one of the set's resources reads it: the resize is ordered after the
    // systems before it in the recipe and before those after it. Without this, a resizing
    // system and one sharing no declared column with it (one that only zeroes a column) ran
    // concurrently while the column was reallocated.
    struct Plain {
        std::vector<std::string> reads, writes;
    };
    std::vector<Plain> accesses;
    for (const Access& a : declared) accesses.push_back({a.reads(), a.writes()});
    for (const SetId set : {SetId::Fluid, SetId::Boundary}) {
        const std::string prefix = std::string(set_name(set)) + ".";
        const std::string count = prefix + "count";
        bool any = false;
        for (const Access& a : declared) any = any || a.resizes_set(set);
        if (!any) continue;
        for (std::size_t i = 0; i < accesses.size(); ++i) {
            Plain& a = accesses[i];
            if (declared[i].resizes_set(set)) {
                a.writes.push_back(count);
                continue;
            }
            const auto in_set = [&](const std::string& r) { return r.rfind(prefix, 0) == 0; };
            if (std::any_of(a.reads.begin(), a.reads.end(), in_set) ||
                std::any_of(a.writes.begin(), a.writes.end(), in_set))
                a.reads.push_back(count);
        }
    }
    std::vector<Edge> edges;
    std::map<std::string, std::size_t> last_writer;
    std::map<std::string, std::vector<std::size_t>> readers;  // since the last write
    auto add = [&](std::size_t from, std::size_t to) {
        if (from != to) edges.emplace_back(from, to);
    };
    for (std::size_t i = 0; i < accesses.size(); ++i) {
        const Plain& a = accesses[i];
        for (const auto& r : a.reads)
            if (auto it = last_writer.find(r); it != last_writer.end()) add(it->second, i);
        for (const auto& w : a.writes) {
            if (auto it = last_writer.find(w); it != last_writer.end()) add(it->second, i);
            for (std::size_t rd : readers[w]) add(rd, i);
        }
        for (const auto& w : a.writes) {
            last_writer[w] = i;
            readers[w].clear();
        }
        for (const auto& r : a.reads)
            if (std::find(a.writes.begin(), a.writes.end(), r) == a.writes.end()) readers[r].push_back(i);
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    return edges;
}

struct SystemGraph::Impl {
    tbb::flow::graph graph;
    tbb::flow::broadcast_node<tbb::flow::continue_msg> start{graph};
    std::vector<std::unique_ptr<tbb::flow::continue_node<tbb::flow::continue_msg>>> nodes;
    std::mutex error_mutex;
    std::exception_ptr error;
};

SystemGraph::SystemGraph(std::vector<std::unique_ptr<System>> systems, World& world)
    : m_systems(std::move(systems)), m_impl(std::make_unique<Impl>()) {
    for (std::size_t i = 0; i < m_systems.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j)
            if (m_systems[j]->name() == m_systems[i]->name())
                throw std::logic_error("two systems of one graph are named '" + m_systems[i]->name() +
                                       "' (a name keys the node, its timing and diagnostics)");
        m_accesses.push_back(m_systems[i]->access());
    }
    m_edges = derive_edges(m_accesses);
    // A system's counters exist (as zero) from the start, so the recorder sees every declared one.
    for (const Access& a : m_accesses)
        for (const auto& c : a.counters()) world.counters.try_emplace(c, 0);
    for (std::size_t i = 0; i < m_systems.size(); ++i)
        m_contexts.push_back(std::make_unique<Context>(world, m_systems[i]->name(), m_accesses[i]));
    m_last.assign(m_systems.size(), 0.0);
    m_total.assign(m_systems.size(), 0.0);

    using namespace tbb::flow;
    for (std::size_t i = 0; i < m_systems.size(); ++i) {
        System* sys = m_systems[i].get();
        m_impl->nodes.push_back(std::make_unique<continue_node<continue_msg>>(
            m_impl->graph, [this, sys, i](const continue_msg&) {
                const auto t0 = std::chrono::steady_clock::now();
                {  // after a failure, the rest of this step is skipped
                    std::lock_guard lock(m_impl->error_mutex);
                    if (m_impl->error) return continue_msg();
                }
                try {
                    sys->run(*m_contexts[i]);
                    if (m_after) m_after(i);
                } catch (...) {
                    std::lock_guard lock(m_impl->error_mutex);
                    if (!m_impl->error) m_impl->error = std::current_exception();
                }
                const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                m_last[i] = s;  // each node runs once per graph run: no race
                m_total[i] += s;
                return continue_msg();
            }));
    }
    std::vector<bool> has_pred(m_systems.size(), false);
    for (auto [from, to] : m_edges) {
        make_edge(*m_impl->nodes[from], *m_impl->nodes[to]);
        has_pred[to] = true;
    }
    for (std::size_t i = 0; i < m_systems.size(); ++i)
        if (!has_pred[i]) make_edge(m_impl->start, *m_impl->nodes[i]);
}

SystemGraph::~SystemGraph() = default;

void SystemGraph::run() {
    m_impl->error = nullptr;
    m_impl->start.try_put(tbb::flow::continue_msg());
    m_impl->graph.wait_for_all();
    if (m_impl->error) std::rethrow_exception(m_impl->error);
}

std::string SystemGraph::dot() const {
    std::ostringstream os;
    os << "digraph systems {\n  rankdir=TB;\n  node [shape=box, fontname=\"monospace\"];\n";
    for (std::size_t i = 0; i < m_systems.size(); ++i) {
        const Access& a = m_accesses[i];
        os << "  n" << i << " [label=\"" << m_systems[i]->name() << "\\nreads:";
        for (const auto& r : a.reads()) os << ' ' << r;
        os << "\\nwrites:";
        for (const auto& w : a.writes()) os << ' ' << w;
        for (const SetId set : a.resized_sets()) os << "\\nresizes: " << set_name(set);
        os << "\"];\n";
    }
    for (auto [from, to] : m_edges) os << "  n" << from << " -> n" << to << ";\n";
    os << "}\n";
    return os.str();
}

}  // namespace sph

namespace sph {

void run_system(System& system, World& world) {
    const Access access = system.access();
    for (const auto& c : access.counters()) world.counters.try_emplace(c, 0);
    Context ctx(world, system.name(), access);
    system.run(ctx);
}

}  // namespace sph
