#include "engine/component_store.hpp"

#include <tbb/parallel_for_each.h>

namespace sph {

void ComponentStore::permute(std::span<const Index> perm) {
    std::vector<ColumnBase*> cols;
    for (auto& [name, col] : m_columns) cols.push_back(col.get());
    tbb::parallel_for_each(cols.begin(), cols.end(), [&](ColumnBase* c) { c->permute(perm); });
}

}  // namespace sph
