#include <gtest/gtest.h>

#include "engine/core/component_store.hpp"

using namespace sph;

namespace {
constexpr Component<Vec3> kPos{"position"};
constexpr Component<Real> kRho{"density"};
constexpr Component<std::uint32_t> kId{"id"};
}  // namespace

TEST(ComponentStore, RegistersOnlyWhatIsAskedAndZeroes) {
    ComponentStore s;
    s.add(kPos);
    s.resize(5);
    EXPECT_TRUE(s.has("position"));
    EXPECT_FALSE(s.has("density"));
    EXPECT_THROW(s.get(kRho), std::logic_error);
    for (const auto& p : s.get(kPos)) EXPECT_EQ(p.norm(), 0);
    auto rho = s.add(kRho);  // added later: sized to the current count
    EXPECT_EQ(rho.size(), 5u);
    EXPECT_THROW(s.get(Component<Real>{"position"}), std::logic_error);  // wrong type
}

TEST(ComponentStore, OnePermutationAppliesToEveryColumn) {
    ComponentStore s;
    s.add(kPos);
    s.add(kRho);
    s.add(kId);
    s.resize(4);
    for (std::uint32_t i = 0; i < 4; ++i) {
        s.get(kPos)[i] = Vec3(Real(i), 0, 0);
        s.get(kRho)[i] = Real(10 * i);
        s.get(kId)[i] = i;
    }
    const std::vector<Index> perm{2, 0, 3, 1};
    s.permute(perm);
    for (std::uint32_t i = 0; i < 4; ++i) {
        EXPECT_EQ(s.get(kId)[i], perm[i]);
        EXPECT_EQ(s.get(kRho)[i], Real(10 * perm[i]));
        EXPECT_EQ(s.get(kPos)[i].x(), Real(perm[i]));
    }
    EXPECT_EQ(s.bytes(), 4 * (sizeof(Vec3) + sizeof(Real) + sizeof(std::uint32_t)));
}
