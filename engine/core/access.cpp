#include "engine/core/access.hpp"

namespace sph {

Access& Access::merge(const Access& other) {
    // A copy in one part stays a copy unless the other part computes that column.
    std::vector<std::string> copies;
    for (const Access* part : {static_cast<const Access*>(this), &other})
        for (const auto& k : part->m_copies)
            if ((is_copy(k) || !may_write(k)) && (other.is_copy(k) || !other.may_write(k))) add(copies, k);
    m_copies = std::move(copies);
    for (const auto& k : other.m_reads) add(m_reads, k);
    for (const auto& k : other.m_writes) add(m_writes, k);
    for (SetId s : other.m_resizes) resizes(s);
    if (m_rows != other.m_rows) m_rows.clear();  // rows of one part only: any row may be written
    return *this;
}

std::vector<std::string> Access::counters() const {
    constexpr std::string_view prefix = "counter.";
    std::vector<std::string> out;
    for (const auto& k : m_writes)
        if (k.rfind(prefix, 0) == 0) out.push_back(k.substr(prefix.size()));
    return out;
}

}  // namespace sph
