// ThreadSanitizer canary (tools/test.sh, stage 3): two flow-graph nodes with no edge between
// them write one variable, and both are forced to run at the same time. The stage requires
// TSan to report this race; a build where TSan cannot see through oneTBB (or is not active)
// would pass the real tests vacuously, and this program exits 0 there, which fails the stage.
#include <tbb/flow_graph.h>

#include <atomic>
#include <cstdio>
#include <thread>

int main() {
    long shared = 0;
    std::atomic<int> started{0};
    const auto body = [&](long increment) {
        started.fetch_add(1, std::memory_order_relaxed);
        while (started.load(std::memory_order_relaxed) < 2) std::this_thread::yield();  // both at once
        for (int i = 0; i < 1000; ++i) shared += increment;  // the race
    };
    tbb::flow::graph g;
    tbb::flow::broadcast_node<tbb::flow::continue_msg> start(g);
    tbb::flow::continue_node<tbb::flow::continue_msg> a(g, [&](tbb::flow::continue_msg) { body(1); });
    tbb::flow::continue_node<tbb::flow::continue_msg> b(g, [&](tbb::flow::continue_msg) { body(2); });
    tbb::flow::make_edge(start, a);
    tbb::flow::make_edge(start, b);
    start.try_put(tbb::flow::continue_msg());
    g.wait_for_all();
    std::printf("%ld\n", shared);
    return 0;
}
