// The graph builder derives exactly the edges the declared accesses imply (EnTT's organizer
// test, with dummy systems named after their access).
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>

#include "engine/system_graph.hpp"
#include "engine/world.hpp"

using namespace sph;

namespace {

class Dummy final : public System {
public:
    Dummy(std::string name, Access a, std::vector<std::string>* log, std::mutex* m)
        : m_name(std::move(name)), m_access(std::move(a)), m_log(log), m_mutex(m) {}
    std::string name() const override { return m_name; }
    Access access() const override { return m_access; }
    void run(World&) override {
        std::lock_guard lock(*m_mutex);
        m_log->push_back(m_name);
    }

private:
    std::string m_name;
    Access m_access;
    std::vector<std::string>* m_log;
    std::mutex* m_mutex;
};

}  // namespace

TEST(DeriveEdges, ReadAfterWriteWriteAfterReadWriteAfterWrite) {
    // 0 writes_pos, 1 reads_pos_writes_rho, 2 reads_pos_writes_grid (independent of 1),
    // 3 reads_rho_grid_writes_acc, 4 reads_acc_writes_pos_vel (WAR on pos vs 1,2; RAW on acc),
    // 5 writes_rho (WAW after 1, WAR after 3)
    std::vector<Access> a{
        {{}, {"pos"}},
        {{"pos"}, {"rho"}},
        {{"pos"}, {"grid"}},
        {{"rho", "grid"}, {"acc"}},
        {{"acc"}, {"pos", "vel"}},
        {{}, {"rho"}},
    };
    const std::vector<Edge> expect{{0, 1}, {0, 2}, {0, 4}, {1, 3}, {1, 4}, {1, 5}, {2, 3}, {2, 4}, {3, 4}, {3, 5}};
    EXPECT_EQ(derive_edges(a), expect);
}

TEST(DeriveEdges, IndependentReadersHaveNoEdge) {
    std::vector<Access> a{{{"x"}, {"a"}}, {{"x"}, {"b"}}, {{"x"}, {"c"}}};
    EXPECT_TRUE(derive_edges(a).empty());
}

TEST(DeriveEdges, ReadWriteSameResourceChainsInOrder) {
    std::vector<Access> a{{{"v"}, {"v"}}, {{"v"}, {"v"}}, {{"v"}, {}}};
    const std::vector<Edge> expect{{0, 1}, {1, 2}};
    EXPECT_EQ(derive_edges(a), expect);
}

TEST(DeriveEdges, ResizingTheFluidSetOrdersEveryFluidAccess) {
    // The PCISPH recipe with an emitter: 0 step size, 1 emitter (resizes every fluid column),
    // 2 a system that only zeroes a column no one else declared, 3 one that touches no fluid
    // resource. 2 must follow 1 (before the fix the two ran concurrently while the column was
    // reallocated: ASan run of Emitter.NeverInsertsInsideParticlesOrBoundaries); 3 stays free.
    // The step-size system reads a fluid column before the resize, so 1 must follow it too.
    std::vector<Access> a{
        {{"fluid.velocity"}, {"step.dt"}},
        {{"step.dt"}, {"fluid.position", "fluid.velocity", "fluid.count"}},
        {{}, {"fluid.pressure_acceleration"}},
        {{"boundary.position"}, {"boundary.grid"}},
    };
    const std::vector<Edge> expect{{0, 1}, {1, 2}};
    EXPECT_EQ(derive_edges(a), expect);
    // Without a writer of fluid.count nothing changes: fluid systems sharing no column stay free.
    a[1].writes.pop_back();
    EXPECT_EQ(derive_edges(a), (std::vector<Edge>{{0, 1}}));
}

// Running the flow graph respects every edge, runs every node once per run, and rethrows a
// system's exception while skipping what follows it.
TEST(SystemGraph, RunsInDependencyOrder) {
    std::vector<std::string> log;
    std::mutex m;
    std::vector<std::unique_ptr<System>> systems;
    systems.push_back(std::make_unique<Dummy>("writes_pos", Access{{}, {"pos"}}, &log, &m));
    systems.push_back(std::make_unique<Dummy>("reads_pos_writes_rho", Access{{"pos"}, {"rho"}}, &log, &m));
    systems.push_back(std::make_unique<Dummy>("reads_pos_writes_grid", Access{{"pos"}, {"grid"}}, &log, &m));
    systems.push_back(std::make_unique<Dummy>("reads_rho_grid_writes_acc", Access{{"rho", "grid"}, {"acc"}}, &log, &m));
    World world;
    SystemGraph g(std::move(systems), world);
    for (int run = 0; run < 50; ++run) {
        log.clear();
        g.run();
        ASSERT_EQ(log.size(), 4u);
        EXPECT_EQ(log.front(), "writes_pos");
        EXPECT_EQ(log.back(), "reads_rho_grid_writes_acc");
    }
    for (std::size_t i = 0; i < 4; ++i) EXPECT_GE(g.total_seconds(i), 0.0);
}

class Thrower final : public System {
public:
    std::string name() const override { return "throws"; }
    Access access() const override { return {{}, {"a"}}; }
    void run(World&) override { throw std::runtime_error("boom"); }
};

TEST(SystemGraph, RethrowsAndSkipsDependents) {
    std::vector<std::string> log;
    std::mutex m;
    std::vector<std::unique_ptr<System>> systems;
    systems.push_back(std::make_unique<Thrower>());
    systems.push_back(std::make_unique<Dummy>("reads_a", Access{{"a"}, {"b"}}, &log, &m));
    World world;
    SystemGraph g(std::move(systems), world);
    EXPECT_THROW(g.run(), std::runtime_error);
    EXPECT_TRUE(log.empty());
}
