#include "engine/core/component_store.hpp"

#include <tbb/parallel_for_each.h>

namespace sph {

void ComponentStore::permute(std::span<const Index> perm) {
    ++m_layout;
    std::vector<ColumnBase*> cols;
    for (auto& [name, col] : m_columns) cols.push_back(col.get());
    tbb::parallel_for_each(cols.begin(), cols.end(), [&](ColumnBase* c) { c->permute(perm); });
}

void ComponentStore::save(Snapshot& out) const {
    std::vector<std::pair<ColumnBase*, const ColumnBase*>> jobs;
    for (const auto& [name, col] : m_columns) {
        auto it = out.columns.find(name);
        if (it == out.columns.end() || it->second->type() != col->type())
            it = out.columns.insert_or_assign(name, col->empty_clone()).first;
        jobs.emplace_back(it->second.get(), col.get());
    }
    out.size = m_size;
    tbb::parallel_for_each(jobs.begin(), jobs.end(), [](const auto& j) { j.first->assign(*j.second); });
}

void ComponentStore::restore(const Snapshot& in) {
    std::vector<std::pair<ColumnBase*, const ColumnBase*>> jobs;
    for (auto& [name, col] : m_columns) {
        auto it = in.columns.find(name);
        if (it == in.columns.end()) {
            col->resize(in.size);
            continue;
        }
        jobs.emplace_back(col.get(), it->second.get());
    }
    m_size = in.size;
    ++m_layout;
    ++m_membership;
    tbb::parallel_for_each(jobs.begin(), jobs.end(), [](const auto& j) { j.first->assign(*j.second); });
}

}  // namespace sph
