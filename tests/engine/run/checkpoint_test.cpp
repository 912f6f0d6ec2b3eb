// Checkpoints: a run continued from a checkpoint equals the uninterrupted run bit for bit, in
// every stepping mode and with a moving boundary (individual stepping keeps neighbour lists
// and base states across steps, so this checks that all of them are saved); damaged files,
// another version or precision, and a checkpoint of another scene are refused with a message.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "engine/run/checkpoint.hpp"
#include "engine/run/state_ring.hpp"
#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

namespace fs = std::filesystem;

Scene stirred_tank(SteppingMode mode) {
    Scene s = test::tank_scene(Vec3d(0.3, 0.12, 0.1), Vec3d(0.3, 0.25, 0.1));
    s.fluid_blocks[0].hydrostatic = true;
    BoundaryDesc paddle;
    paddle.shape = BoundaryShape::Box;
    paddle.box = Aabb{Vec3d(0.13, 0.14, 0.03), Vec3d(0.17, 0.2, 0.07)};
    Motion m;
    m.type = MotionType::Sinusoidal;
    m.axis = Vec3d(1, 0, 0);
    m.amplitude = 0.05;
    m.period = 0.2;
    paddle.motion = m;
    s.boundaries.push_back(paddle);
    s.simulation.stepping.mode = mode;
    s.simulation.stepping.dt = 2e-4;
    s.simulation.sort_interval = 7;  // sorts fall on both sides of the checkpoint
    return s;
}

/// Every column of both particle sets, the step scalars and the lists, as bytes.
std::string state_bytes(const World& w) {
    std::string s;
    for (const ComponentStore* store : {&w.fluid.store, &w.boundary.store})
        for (const auto& name : store->names()) {
            const auto raw = store->raw(name);
            s += name;
            s.append(reinterpret_cast<const char*>(raw.data()), raw.size());
        }
    s.append(reinterpret_cast<const char*>(&w.clock.t_ticks), sizeof w.clock.t_ticks);
    s.append(reinterpret_cast<const char*>(&w.clock.step), sizeof w.clock.step);
    s.append(reinterpret_cast<const char*>(&w.step_size.dt_ticks), sizeof w.step_size.dt_ticks);
    const std::vector<Index> counts = w.fluid_neighbours.counts();
    s.append(reinterpret_cast<const char*>(counts.data()), counts.size() * sizeof(Index));
    return s;
}

std::string read_all(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_all(const fs::path& p, const std::string& s) {
    std::ofstream(p, std::ios::binary) << s;
}

template <class F>
std::string checkpoint_error(F&& f) {
    try {
        f();
    } catch (const CheckpointError& e) {
        return e.what();
    }
    return "<no error>";
}

/// A directory of this test's own: ctest runs the tests of this file as separate processes at
/// the same time, so a shared directory removed by one test vanished under another (seen in an
/// ASan stage).
fs::path test_dir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    return fs::temp_directory_path() / (std::string("sph_checkpoint_test_") + info->name());
}

}  // namespace

TEST(Checkpoint, ResumedRunIsBitIdenticalInEveryMode) {
    const fs::path k_dir = test_dir();
    fs::create_directories(k_dir);
    // `individual` under both activation rules; `paper` leaves part of the fluid asleep at the
    // checkpoint, which is the case that needs the saved neighbour lists.
    const std::pair<SteppingMode, Activation> runs[] = {{SteppingMode::Constant, Activation::Deadline},
                                                        {SteppingMode::Global, Activation::Deadline},
                                                        {SteppingMode::Individual, Activation::Deadline},
                                                        {SteppingMode::Individual, Activation::Paper},
                                                        {SteppingMode::Binned, Activation::Deadline}};
    for (const auto& [mode, rule] : runs) {
        Scene s = stirred_tank(mode);
        s.simulation.stepping.activation = rule;
        // binned: without the acoustic condition the bins differ, so the resumed run must
        // rebuild its due-time buckets from the saved ends and continue on the saved timeline.
        if (mode == SteppingMode::Binned) s.simulation.stepping.acoustic = false;
        const fs::path file = k_dir / (std::string(to_string(mode)) + "_" + to_string(rule) + ".sphckpt");
        auto a = make_simulation(s);
        for (int k = 0; k < 60; ++k) a->step();
        write_checkpoint(file, *a, {{"note", "test"}});
        std::uint64_t fewest_active = a->world().fluid.size();
        for (int k = 0; k < 90; ++k) {
            a->step();
            fewest_active = std::min(fewest_active, a->world().counter_value("active"));
        }

        auto b = make_simulation(s);
        const Checkpoint ck = read_checkpoint(file);
        EXPECT_EQ(ck.meta["note"], "test");
        restore_checkpoint(*b, ck);
        EXPECT_EQ(b->steps(), 60);
        // binned re-sorts by the rows evaluated since the last sort (Simulation::sort_due): the
        // count is part of the saved state, and a sort falls after the checkpoint.
        const std::uint64_t rows_at_checkpoint = b->world().clock.rows_since_sort;
        int sorts_after = 0;
        for (int k = 0; k < 90; ++k) {
            b->step();
            sorts_after += b->last_step_sorted();
        }
        if (mode == SteppingMode::Binned) {
            EXPECT_GT(rows_at_checkpoint, 0u);
            EXPECT_GT(sorts_after, 0);
        }
        EXPECT_EQ(a->steps(), b->steps());
        EXPECT_TRUE(state_bytes(a->world()) == state_bytes(b->world()))
            << to_string(mode) << ": the resumed run differs from the uninterrupted one";
        if ((mode == SteppingMode::Individual && rule == Activation::Paper) || mode == SteppingMode::Binned) {
            // The case that needs the saved lists (individual) or ends (binned): part of the
            // fluid was asleep in the steps after the checkpoint.
            EXPECT_LT(fewest_active, a->world().fluid.size()) << to_string(mode);
        }
    }
    fs::remove_all(k_dir);
}

// The continuity density (fluid.density: continuity): the density is state, and in `global`
// the time it was last advanced to is a kept resource; a resumed run equals the uninterrupted
// one in the three modes that advance it differently (per step, per evaluation, per bin).
TEST(Checkpoint, ResumedContinuityDensityRunIsBitIdentical) {
    const fs::path k_dir = test_dir();
    fs::create_directories(k_dir);
    for (const SteppingMode mode : {SteppingMode::Global, SteppingMode::Individual, SteppingMode::Binned}) {
        Scene s = stirred_tank(mode);
        s.fluid.density = DensityForm::Continuity;
        if (mode == SteppingMode::Binned) s.simulation.stepping.acoustic = false;
        const fs::path file = k_dir / (std::string(to_string(mode)) + "_continuity.sphckpt");
        auto a = make_simulation(s);
        for (int k = 0; k < 60; ++k) a->step();
        write_checkpoint(file, *a, nlohmann::json::object());
        for (int k = 0; k < 90; ++k) a->step();
        auto b = make_simulation(s);
        restore_checkpoint(*b, read_checkpoint(file));
        for (int k = 0; k < 90; ++k) b->step();
        EXPECT_TRUE(state_bytes(a->world()) == state_bytes(b->world()))
            << to_string(mode) << ": the resumed continuity run differs from the uninterrupted one";
        // The density clock is global's (individual and binned advance from t_last).
        EXPECT_TRUE(a->world().resources.has("fluid.density_clock") == (mode == SteppingMode::Global));
    }
    fs::remove_all(k_dir);
}

namespace {
/// `glass` filled to 300 particles by its emitter, checkpointed, then 40 steps on, against the
/// same 40 steps after a restore from the checkpoint: equal state bytes.
void expect_resumed_pour_bit_identical(Scene s, const std::string& label) {
    const fs::path k_dir = test_dir();
    fs::create_directories(k_dir);
    s.simulation.frame_rate = 0;
    auto a = make_simulation(s);
    while (a->world().fluid.size() < 300) a->step();  // the emitter has been filling for a while
    const std::int64_t at = a->steps();
    const fs::path file = k_dir / (label + ".sphckpt");
    write_checkpoint(file, *a, nlohmann::json::object());
    for (int k = 0; k < 40; ++k) a->step();

    auto b = make_simulation(s);
    restore_checkpoint(*b, read_checkpoint(file));
    ASSERT_EQ(b->steps(), at);
    for (int k = 0; k < 40; ++k) b->step();
    EXPECT_EQ(a->world().fluid.size(), b->world().fluid.size());
    EXPECT_GT(a->world().fluid.size(), 300u);
    EXPECT_EQ(a->world().step_size.dt_ticks, b->world().step_size.dt_ticks);
    EXPECT_TRUE(state_bytes(a->world()) == state_bytes(b->world()))
        << "the resumed " << label << " run differs from the uninterrupted one";
    fs::remove_all(k_dir);
}
}  // namespace

// PCISPH `adaptive` with an emitter: the controller's pending step, delta and the emitters'
// budget are Kept resources, so they are in the checkpoint. Before they were (checkpoint
// version 1) a resumed `glass` run took another step at once (1.40 ms instead of 0.72 ms at step
// 98) and emitted 759 particles instead of 756; this test would have failed there.
TEST(Checkpoint, ResumedPcisphAdaptiveRunWithEmitterIsBitIdentical) {
    Scene s = load_scene(SPH_SOURCE_DIR "/scenes/glass.json");
    expect_resumed_pour_bit_identical(s, "pcisph_adaptive");
}

// PCISPH's shock rollback (Ihmsen et al. 2010 Alg. 2, eq. 25-27) goes back two steps: a
// checkpoint taken just before the step that detects a shock carries the rollback ring's states
// ("ring/<k>/..." sections), so the resumed run goes back as far as the uninterrupted one. On
// `glass`, the first shock's step found in a first run; a second run checkpointed just before it
// and continued 40 steps, against the same 40 steps from the checkpoint. Before the ring was
// checkpointed (until 2026-12-07) the resumed rollback reached one step and the runs differed.
TEST(Checkpoint, ResumedPcisphRunRollsBackAsFarAsTheUninterruptedOne) {
    const fs::path k_dir = test_dir();
    fs::create_directories(k_dir);
    Scene s = load_scene(SPH_SOURCE_DIR "/scenes/glass.json");
    s.simulation.frame_rate = 0;
    std::int64_t shock_step = -1;
    {
        auto a = make_simulation(s);
        while (shock_step < 0 && a->steps() < 20000) {
            a->step();
            if (a->last().rolled_back) shock_step = a->last().step;
        }
    }
    ASSERT_GE(shock_step, 2) << "no shock in the first 20,000 steps of glass";
    auto b = make_simulation(s);
    while (b->steps() < shock_step) b->step();
    const fs::path file = k_dir / "pcisph_shock.sphckpt";
    write_checkpoint(file, *b, nlohmann::json::object());
    ASSERT_EQ(b->ring()->size(), 2u);  // the ring is full: the rollback can go two steps back
    b->step();
    ASSERT_TRUE(b->last().rolled_back);
    const std::int64_t b_back_to = b->world().clock.t_ticks;
    for (int k = 0; k < 40; ++k) b->step();

    auto c = make_simulation(s);
    restore_checkpoint(*c, read_checkpoint(file));
    ASSERT_EQ(c->ring()->size(), 2u);
    c->step();
    ASSERT_TRUE(c->last().rolled_back);
    EXPECT_EQ(c->world().clock.t_ticks, b_back_to);  // back to the same time: two steps, not one
    for (int k = 0; k < 40; ++k) c->step();
    EXPECT_TRUE(state_bytes(b->world()) == state_bytes(c->world()))
        << "the run resumed before the shock at step " << shock_step << " differs from the uninterrupted one";
    std::printf("glass: first shock at step %lld; resumed just before it, rolled back to t = %.6g s as the "
                "uninterrupted run\n", static_cast<long long>(shock_step), to_seconds(b_back_to));
    fs::remove_all(k_dir);
}

// DFSPH on `glass` (its method replaced, as `--method dfsph` does): the warm-start totals are
// Kept columns and the emitter's budget a Kept resource, so a resumed run equals the
// uninterrupted one bit for bit.
TEST(Checkpoint, ResumedDfsphRunWithEmitterIsBitIdentical) {
    Scene s = load_scene(SPH_SOURCE_DIR "/scenes/glass.json", {{"/simulation/method", "dfsph"}});
    ASSERT_EQ(s.simulation.stepping.mode, SteppingMode::Adaptive);
    expect_resumed_pour_bit_identical(s, "dfsph");
}

TEST(Checkpoint, DamagedFilesAreRefusedWithTheReason) {
    const fs::path k_dir = test_dir();
    fs::create_directories(k_dir);
    const Scene s = stirred_tank(SteppingMode::Global);
    auto sim = make_simulation(s);
    for (int k = 0; k < 5; ++k) sim->step();
    const fs::path good = k_dir / "good.sphckpt", bad = k_dir / "bad.sphckpt";
    write_checkpoint(good, *sim, nlohmann::json::object());
    const std::string bytes = read_all(good);
    ASSERT_GT(bytes.size(), 1000u);

    std::string flipped = bytes;
    flipped[bytes.size() / 2] ^= 0x10;  // one bit in the middle of the payload
    write_all(bad, flipped);
    EXPECT_NE(checkpoint_error([&] { read_checkpoint(bad); }).find(": checksum mismatch (stored "), std::string::npos);

    // A version-1 checkpoint (the step state as raw bytes, before counters were stored by
    // name) is refused by its version number.
    std::string v1 = bytes;
    v1[8] = 1;  // format version field
    write_all(bad, v1);
    EXPECT_EQ(checkpoint_error([&] { read_checkpoint(bad); }),
              bad.string() + ": checkpoint format version 1, expected version 2 (written by another version of sph)");

    std::string precision = bytes;
    precision[12] = char(sizeof(Real) == 4 ? 8 : 4);
    write_all(bad, precision);
    EXPECT_NE(checkpoint_error([&] { read_checkpoint(bad); }).find("(SPH_DOUBLE differs)"), std::string::npos);

    write_all(bad, bytes.substr(0, bytes.size() - 100));
    EXPECT_EQ(checkpoint_error([&] { read_checkpoint(bad); }),
              bad.string() + ": holds " + std::to_string(bytes.size() - 32 - 100) + " payload bytes, the header says " +
                  std::to_string(bytes.size() - 32) + " (truncated?)");

    // A section length that wraps the read position round to the section's own start (2^64 minus
    // its header's 12 + name bytes), under a valid checksum: the reader used to read that section
    // for ever (the robustness issue, defect 4); now it names the overrun.
    {
        std::string wrapped = bytes;
        std::uint32_t nlen = 0;
        std::memcpy(&nlen, wrapped.data() + 32, 4);  // the first section's name length
        const std::uint64_t huge = std::uint64_t(0) - (4 + nlen + 8);
        std::memcpy(wrapped.data() + 32 + 4 + nlen, &huge, 8);  // its data length
        std::uint64_t h = 14695981039346656037ull;  // FNV-1a 64 of the payload, as the writer does
        for (std::size_t k = 32; k < wrapped.size(); ++k) h = (h ^ std::uint8_t(wrapped[k])) * 1099511628211ull;
        std::memcpy(wrapped.data() + 24, &h, 8);
        write_all(bad, wrapped);
        EXPECT_EQ(checkpoint_error([&] { read_checkpoint(bad); }),
                  bad.string() + ": a section runs past the end of the payload");
    }

    write_all(bad, "{\"name\": \"a scene, not a checkpoint\"}");
    EXPECT_EQ(checkpoint_error([&] { read_checkpoint(bad); }),
              bad.string() + ": not an sph checkpoint (expected the magic \"SPHCKPT\" at the start)");

    EXPECT_NE(checkpoint_error([&] { read_checkpoint(k_dir / "missing.sphckpt"); })
                  .find("missing.sphckpt: cannot open checkpoint file (No such file or directory)"),
              std::string::npos);

    // Sections whose checksum is valid but whose indices are not (a crafted or mis-written file):
    // a neighbour entry or an active row beyond the fluid, refused naming the section, before
    // anything reads them.
    {
        Checkpoint ck = read_checkpoint(good);
        std::string& lists = ck.sections.at("fluid_neighbours");
        std::uint64_t nc = 0;
        std::memcpy(&nc, lists.data() + 8, 8);
        ASSERT_GT(nc, 0u);
        const Index beyond = Index(sim->world().fluid.size() + 7);
        std::memcpy(lists.data() + 24 + nc * sizeof(Index), &beyond, sizeof(Index));  // the first entry
        auto fresh = make_simulation(s);
        EXPECT_NE(checkpoint_error([&] { restore_checkpoint(*fresh, ck); })
                      .find("section 'fluid_neighbours' "),
                  std::string::npos);
        Checkpoint ck2 = read_checkpoint(good);
        ck2.sections.at("active_set").append(reinterpret_cast<const char*>(&beyond), sizeof(Index));
        auto fresh2 = make_simulation(s);
        EXPECT_NE(checkpoint_error([&] { restore_checkpoint(*fresh2, ck2); })
                      .find("section 'active_set' names particle " + std::to_string(beyond)),
                  std::string::npos);
    }

    // A checkpoint of another method (individual registers more columns) is refused.
    auto other = make_simulation(stirred_tank(SteppingMode::Individual));
    EXPECT_NE(checkpoint_error([&] { restore_checkpoint(*other, read_checkpoint(good)); })
                  .find("are not the ones this scene's method uses"),
              std::string::npos);
    // And one of another geometry (a wider tank samples other boundary particles).
    Scene wide = stirred_tank(SteppingMode::Global);
    wide.boundaries[0].box.max.x() = 0.32;
    auto wider = make_simulation(wide);
    EXPECT_NE(checkpoint_error([&] { restore_checkpoint(*wider, read_checkpoint(good)); })
                  .find("the boundary particles differ from this scene's sampling"),
              std::string::npos);
    fs::remove_all(k_dir);
}

// The rollback ring after the world was replaced (restore_checkpoint calls
// Simulation::forget_history): no state of the old world may be restored. Two states saved, the
// ring cleared: a rollback restores nothing and leaves the world as it is; saved again, it
// restores that new state.
TEST(StateRing, ClearDropsEveryState) {
    auto sim = make_simulation(stirred_tank(SteppingMode::Global));
    World& w = sim->world();
    // What a ring state holds (the columns and the clock; the lists are rebuilt every step).
    auto held = [&] {
        std::string s;
        for (const ComponentStore* store : {&w.fluid.store, &w.boundary.store})
            for (const auto& name : store->names()) {
                const auto raw = store->raw(name);
                s.append(reinterpret_cast<const char*>(raw.data()), raw.size());
            }
        s.append(reinterpret_cast<const char*>(&w.clock.t_ticks), sizeof w.clock.t_ticks);
        return s;
    };
    StateRing ring(2);
    ring.save(w);
    sim->step();
    ring.save(w);
    ASSERT_EQ(ring.size(), 2u);
    sim->step();
    const std::string now = held();
    ring.clear();
    EXPECT_EQ(ring.size(), 0u);
    EXPECT_EQ(ring.restore(w, 2), 0u);
    EXPECT_TRUE(held() == now) << "a cleared ring restored a state";
    ring.save(w);
    sim->step();
    ASSERT_FALSE(held() == now);
    EXPECT_EQ(ring.restore(w, 2), 1u);  // only the state saved after the clear
    EXPECT_TRUE(held() == now) << "the state saved after the clear";
}
