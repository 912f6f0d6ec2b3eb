#pragma once
/// @file component_store.hpp
/// @brief One contiguous column per particle attribute; a method registers only the columns it
/// needs, and one permutation (the z-order sort) is applied to every registered column.
#include <cstddef>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "engine/core/types.hpp"

namespace sph {

/// @brief Typed name of a column. Components are declared once (engine/components.hpp) and
/// looked up by name, so a typo is a compile error rather than a silent new column.
template <class T>
struct Component {
    std::string_view name;
    using value_type = T;
};

/// @brief Type-erased column so the store can resize and permute without knowing T.
class ColumnBase {
public:
    virtual ~ColumnBase() = default;
    virtual void resize(std::size_t n) = 0;
    /// new[i] = old[perm[i]]
    virtual void permute(std::span<const Index> perm) = 0;
    virtual std::size_t bytes() const = 0;
    virtual const std::type_info& type() const = 0;
    /// @brief An empty column of the same type (for snapshots).
    virtual std::unique_ptr<ColumnBase> empty_clone() const = 0;
    /// @brief Copies the values of a column of the same type (reusing this column's storage).
    virtual void assign(const ColumnBase& other) = 0;
    /// @brief Bytes of one element (checkpoints copy columns as raw bytes).
    virtual std::size_t element_size() const = 0;
    /// @brief The column's elements as raw bytes (size() * element_size()).
    virtual std::span<std::byte> raw() = 0;
};

/// @brief The value new column entries get: zero (Eigen's default constructor leaves
/// vectors uninitialised, so they are zeroed explicitly).
template <class T>
T zero_value() {
    if constexpr (requires { T::Zero(); })
        return T::Zero();
    else
        return T{};
}

template <class T>
class Column final : public ColumnBase {
public:
    std::vector<T> data;
    void resize(std::size_t n) override { data.resize(n, zero_value<T>()); }
    void permute(std::span<const Index> perm) override {
        m_scratch.resize(data.size());
        for (std::size_t i = 0; i < perm.size(); ++i) m_scratch[i] = data[perm[i]];
        data.swap(m_scratch);
    }
    std::size_t bytes() const override { return data.capacity() * sizeof(T); }
    const std::type_info& type() const override { return typeid(T); }
    std::unique_ptr<ColumnBase> empty_clone() const override { return std::make_unique<Column<T>>(); }
    void assign(const ColumnBase& other) override {
        const auto& src = static_cast<const Column<T>&>(other).data;
        data.assign(src.begin(), src.end());
    }
    std::size_t element_size() const override { return sizeof(T); }
    std::span<std::byte> raw() override { return std::as_writable_bytes(std::span<T>(data)); }

private:
    std::vector<T> m_scratch;
};

/// @brief The columns of one particle set (fluid or boundary).
class ComponentStore {
public:
    /// @brief Registers a column (idempotent) sized to the current particle count.
    template <class T>
    std::span<T> add(Component<T> c) {
        auto it = m_columns.find(c.name);
        if (it == m_columns.end()) {
            auto col = std::make_unique<Column<T>>();
            col->resize(m_size);
            it = m_columns.emplace(std::string(c.name), std::move(col)).first;
        }
        return column<T>(c.name, *it->second).data;
    }

    template <class T>
    std::span<T> get(Component<T> c) {
        return column<T>(c.name, find(c.name)).data;
    }
    template <class T>
    std::span<const T> get(Component<T> c) const {
        return column<T>(c.name, const_cast<ComponentStore*>(this)->find(c.name)).data;
    }

    bool has(std::string_view name) const { return m_columns.find(name) != m_columns.end(); }
    /// @brief Element type of a registered column (throws std::logic_error if unknown).
    const std::type_info& type_of(std::string_view name) const {
        return const_cast<ComponentStore*>(this)->find(name).type();
    }
    /// @brief A registered column as raw bytes, for copying it whole (checkpoints).
    /// @warning Only for trivially copyable element types (every engine component is).
    std::span<std::byte> raw(std::string_view name) { return find(name).raw(); }
    std::span<const std::byte> raw(std::string_view name) const {
        return const_cast<ComponentStore*>(this)->find(name).raw();
    }
    std::size_t element_size(std::string_view name) const {
        return const_cast<ComponentStore*>(this)->find(name).element_size();
    }
    std::size_t size() const { return m_size; }
    /// @brief Resizes every column; new entries are value-initialised.
    void resize(std::size_t n) {
        m_size = n;
        ++m_layout;
        ++m_membership;
        for (auto& [name, col] : m_columns) col->resize(n);
    }
    /// @brief Changes whenever rows are reordered, added, removed or restored (permute, resize,
    /// restore): a system that keeps row indices across steps rebuilds them when it changes.
    std::uint64_t layout() const { return m_layout; }
    /// @brief Changes whenever rows are added, removed or restored (resize, restore), but not
    /// when they are only reordered: what holds over every row (a bound, a maximum) stays
    /// valid across a reordering.
    std::uint64_t membership() const { return m_membership; }
    /// @brief Applies one permutation to every registered column (new[i] = old[perm[i]]).
    /// Columns are independent, so they are permuted in parallel.
    void permute(std::span<const Index> perm);
    /// @brief Bytes held by one column (0 when it is not registered).
    std::size_t bytes(std::string_view name) const {
        const auto it = m_columns.find(name);
        return it == m_columns.end() ? 0 : it->second->bytes();
    }
    /// @brief Bytes held by all columns.
    std::size_t bytes() const {
        std::size_t b = 0;
        for (const auto& [name, col] : m_columns) b += col->bytes();
        return b;
    }
    /// @brief A copy of every column, by name (a state snapshot, e.g. for a rollback).
    struct Snapshot {
        std::map<std::string, std::unique_ptr<ColumnBase>, std::less<>> columns;
        std::size_t size = 0;
    };
    /// @brief Copies every column into `out`, column by column (reusing its storage).
    void save(Snapshot& out) const;
    /// @brief Restores every column saved in `in` and the size. Columns registered after the
    /// snapshot was taken are resized to its size.
    void restore(const Snapshot& in);

    std::vector<std::string> names() const {
        std::vector<std::string> out;
        for (const auto& [name, col] : m_columns) out.push_back(name);
        return out;
    }

private:
    ColumnBase& find(std::string_view name) {
        auto it = m_columns.find(name);
        if (it == m_columns.end())
            throw std::logic_error("component '" + std::string(name) + "' is not registered");
        return *it->second;
    }
    template <class T>
    static Column<T>& column(std::string_view name, ColumnBase& base) {
        if (base.type() != typeid(T))
            throw std::logic_error("component '" + std::string(name) + "' has another type");
        return static_cast<Column<T>&>(base);
    }

    std::map<std::string, std::unique_ptr<ColumnBase>, std::less<>> m_columns;
    std::size_t m_size = 0;
    std::uint64_t m_layout = 0;
    std::uint64_t m_membership = 0;
};

}  // namespace sph
