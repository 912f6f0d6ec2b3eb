// The graph builder derives exactly the edges the declared accesses imply (EnTT's organizer
// test, with dummy systems named after their access), runs nodes in that order, and the
// per-system Context refuses what a system did not declare.
#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <mutex>

#include "engine/data/components.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "engine/graph/system_graph.hpp"

using namespace sph;

namespace {

// Test resources: plain names, owned by the world's resource store (no World member).
constexpr Resource<int> pos{"pos"}, rho{"rho"}, grid{"grid"}, acc{"acc"}, vel{"vel"}, a_res{"a"}, b_res{"b"},
    x_res{"x"}, c_res{"c"}, v_res{"v"};

class Dummy final : public System {
public:
    Dummy(std::string name, Access a, std::vector<std::string>* log, std::mutex* m)
        : m_name(std::move(name)), m_access(std::move(a)), m_log(log), m_mutex(m) {}
    std::string name() const override { return m_name; }
    Access access() const override { return m_access; }
    void run(Context&) override {
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
        Access().write(pos),
        Access().read(pos).write(rho),
        Access().read(pos).write(grid),
        Access().read(rho, grid).write(acc),
        Access().read(acc).write(pos, vel),
        Access().write(rho),
    };
    const std::vector<Edge> expect{{0, 1}, {0, 2}, {0, 4}, {1, 3}, {1, 4}, {1, 5}, {2, 3}, {2, 4}, {3, 4}, {3, 5}};
    EXPECT_EQ(derive_edges(a), expect);
}

TEST(DeriveEdges, IndependentReadersHaveNoEdge) {
    std::vector<Access> a{Access().read(x_res).write(a_res), Access().read(x_res).write(b_res),
                          Access().read(x_res).write(c_res)};
    EXPECT_TRUE(derive_edges(a).empty());
}

TEST(DeriveEdges, ReadWriteSameResourceChainsInOrder) {
    std::vector<Access> a{Access().read(v_res).write(v_res), Access().read(v_res).write(v_res), Access().read(v_res)};
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
        Access().read(fluid(comp::velocity)).write(res::dt),
        Access().read(res::dt).write(fluid(comp::position), fluid(comp::velocity)).resizes(SetId::Fluid),
        Access().write(fluid(comp::pressure_acceleration)),
        Access().read(boundary(comp::position)).write(res::boundary_grid),
    };
    const std::vector<Edge> expect{{0, 1}, {1, 2}};
    EXPECT_EQ(derive_edges(a), expect);
    // Without the resize nothing changes: fluid systems sharing no column stay free.
    a[1] = Access().read(res::dt).write(fluid(comp::position), fluid(comp::velocity));
    EXPECT_EQ(derive_edges(a), (std::vector<Edge>{{0, 1}}));
}

TEST(Access, KeysOfTypedHandles) {
    const Access a = Access().read(fluid(comp::position), res::fluid_neighbours).write(boundary(comp::pressure),
                                                                                       counter::collisions);
    EXPECT_EQ(a.reads(), (std::vector<std::string>{"fluid.position", "fluid.neighbours"}));
    EXPECT_EQ(a.writes(), (std::vector<std::string>{"boundary.pressure", "counter.collisions"}));
    EXPECT_EQ(a.counters(), (std::vector<std::string>{"collisions"}));
    EXPECT_TRUE(a.may_read("boundary.pressure"));  // a write implies a read
    EXPECT_FALSE(a.may_write("fluid.position"));
}

// copies(): a write like any other (ordered, may_write), marked so that the finiteness trace
// skips it; merged with a part that computes the same column it is no longer a copy.
TEST(Access, CopiesAreWritesTheTraceSkips) {
    const Access a = Access().read(fluid(comp::position)).copies(fluid(comp::position_last)).write(fluid(comp::velocity));
    EXPECT_TRUE(a.may_write("fluid.position_last"));
    EXPECT_TRUE(a.is_copy("fluid.position_last"));
    EXPECT_FALSE(a.is_copy("fluid.velocity"));
    EXPECT_FALSE(a.is_copy("fluid.position"));
    // Ordered against a reader of the copy like any write.
    EXPECT_EQ(derive_edges({a, Access().read(fluid(comp::position_last))}), (std::vector<Edge>{{0, 1}}));
    Access b = a;
    b.merge(Access().write(fluid(comp::position_last)));
    EXPECT_FALSE(b.is_copy("fluid.position_last")) << "computed in one part: checked";
    Access c = a;
    c.merge(Access().read(fluid(comp::position_last)).copies(fluid(comp::velocity_last)));
    EXPECT_TRUE(c.is_copy("fluid.position_last"));
    EXPECT_TRUE(c.is_copy("fluid.velocity_last"));
    Access d = Access().write(fluid(comp::velocity_last));
    d.merge(c);
    EXPECT_FALSE(d.is_copy("fluid.velocity_last"));
    EXPECT_TRUE(d.is_copy("fluid.position_last"));
}

// Running the flow graph respects every edge and runs every node once per run.
TEST(SystemGraph, RunsInDependencyOrder) {
    std::vector<std::string> log;
    std::mutex m;
    std::vector<std::unique_ptr<System>> systems;
    systems.push_back(std::make_unique<Dummy>("writes_pos", Access().write(pos), &log, &m));
    systems.push_back(std::make_unique<Dummy>("reads_pos_writes_rho", Access().read(pos).write(rho), &log, &m));
    systems.push_back(std::make_unique<Dummy>("reads_pos_writes_grid", Access().read(pos).write(grid), &log, &m));
    systems.push_back(
        std::make_unique<Dummy>("reads_rho_grid_writes_acc", Access().read(rho, grid).write(acc), &log, &m));
    World world;
    SystemGraph g(std::move(systems), world);
    std::map<std::string, int> runs;
    for (int run = 0; run < 50; ++run) {
        log.clear();
        g.run();
        ASSERT_EQ(log.size(), 4u);
        EXPECT_EQ(log.front(), "writes_pos");
        EXPECT_EQ(log.back(), "reads_rho_grid_writes_acc");
        for (const auto& name : log) ++runs[name];
    }
    ASSERT_EQ(runs.size(), 4u);  // four distinct nodes, each run once per graph run
    for (const auto& [name, n] : runs) EXPECT_EQ(n, 50) << name;
}

TEST(SystemGraph, RefusesTwoSystemsOfOneName) {
    std::vector<std::string> log;
    std::mutex m;
    std::vector<std::unique_ptr<System>> systems;
    systems.push_back(std::make_unique<Dummy>("global_dt", Access().write(a_res), &log, &m));
    systems.push_back(std::make_unique<Dummy>("global_dt", Access().write(b_res), &log, &m));
    World world;
    EXPECT_THROW(SystemGraph(std::move(systems), world), std::logic_error);
}

class Thrower final : public System {
public:
    std::string name() const override { return "throws"; }
    Access access() const override { return Access().write(a_res); }
    void run(Context&) override { throw std::runtime_error("boom"); }
};

TEST(SystemGraph, RethrowsAndSkipsDependents) {
    std::vector<std::string> log;
    std::mutex m;
    std::vector<std::unique_ptr<System>> systems;
    systems.push_back(std::make_unique<Thrower>());
    systems.push_back(std::make_unique<Dummy>("reads_a", Access().read(a_res).write(b_res), &log, &m));
    World world;
    SystemGraph g(std::move(systems), world);
    EXPECT_THROW(g.run(), std::runtime_error);
    EXPECT_TRUE(log.empty());
}

// ---- the Context enforces the declaration ----

namespace {

/// Declares reading fluid.position and writing fluid.density; its run does what `what` says.
class Trespasser final : public System {
public:
    explicit Trespasser(std::string what) : m_what(std::move(what)) {}
    std::string name() const override { return "reads_pos_writes_rho"; }
    Access access() const override { return Access().read(fluid(comp::position)).write(fluid(comp::density)); }
    void run(Context& ctx) override {
        if (m_what == "declared") {
            auto rho = ctx.write(fluid(comp::density));
            const auto x = ctx.read(fluid(comp::position));
            for (std::size_t i = 0; i < rho.size(); ++i) rho[i] = x[i].x();
            (void)ctx.read(fluid(comp::density));  // reading what it writes is allowed
        } else if (m_what == "write_read_column") {
            (void)ctx.write(fluid(comp::position));  // declared read only
        } else if (m_what == "read_undeclared_column") {
            (void)ctx.read(fluid(comp::velocity));
        } else if (m_what == "read_undeclared_resource") {
            (void)ctx.read(res::fluid_neighbours);
        } else if (m_what == "write_undeclared_counter") {
            ctx.write(counter::collisions) = 1;
        } else if (m_what == "resize") {
            ctx.resize(SetId::Fluid, 10);
        }
    }

private:
    std::string m_what;
};

void fill(World& w) {
    w.fluid.store.add(comp::position);
    w.fluid.store.add(comp::velocity);
    w.fluid.store.add(comp::density);
    w.fluid.store.resize(4);
    auto x = w.fluid.store.get(comp::position);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3(Real(i), 0, 0);
}

}  // namespace

TEST(Context, HandsOutWhatIsDeclared) {
    World w;
    fill(w);
    run_system(Trespasser("declared"), w);
    const auto rho = w.fluid.store.get(comp::density);
    EXPECT_EQ(rho[3], Real(3));
}

// Each seeded undeclared access, run inside a flow graph as in a real step, is caught and the
// error names the system and the key. Remove the check in Context::require and this fails.
TEST(Context, UndeclaredAccessIsCaughtWithSystemAndKey) {
    const std::vector<std::pair<std::string, std::string>> cases{
        {"write_read_column", "'fluid.position'"},
        {"read_undeclared_column", "'fluid.velocity'"},
        {"read_undeclared_resource", "'fluid.neighbours'"},
        {"write_undeclared_counter", "'counter.collisions'"},
        {"resize", "'fluid'"},
    };
    for (const auto& [what, key] : cases) {
        World w;
        fill(w);
        std::vector<std::unique_ptr<System>> systems;
        systems.push_back(std::make_unique<Trespasser>(what));
        SystemGraph g(std::move(systems), w);
        try {
            g.run();
            ADD_FAILURE() << what << ": no AccessError";
        } catch (const AccessError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find("'reads_pos_writes_rho'"), std::string::npos) << msg;
            EXPECT_NE(msg.find(key), std::string::npos) << msg;
        }
        EXPECT_EQ(w.fluid.size(), 4u) << what;  // the resize was refused before it happened
    }
}
