#pragma once
/// @file resources.hpp
/// @brief Resources owned by systems (a method's state that is not a particle column: a solver's
/// coefficients and controller, a source's progress), stored by name with their type. The engine
/// copies the `Kept` ones generically: into rollback snapshots and into checkpoints (as bytes),
/// without knowing what they hold. `Scratch` ones are rebuilt every step and never copied.
#include <concepts>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeinfo>
#include <vector>

namespace sph {

enum class Lifetime { Kept, Scratch };

/// @brief How a resource type becomes bytes: a trivially copyable type is copied as it is;
/// any other type provides `void save(std::string&) const` and `void load(std::string_view)`
/// (load throws std::runtime_error when the bytes do not fit).
template <class T>
concept SelfSerialising = requires(const T& c, T& m, std::string& out, std::string_view in) {
    c.save(out);
    m.load(in);
};

class OwnedResource {
public:
    explicit OwnedResource(Lifetime lifetime) : m_lifetime(lifetime) {}
    virtual ~OwnedResource() = default;
    Lifetime lifetime() const { return m_lifetime; }
    virtual const std::type_info& type() const = 0;
    virtual std::unique_ptr<OwnedResource> clone() const = 0;
    /// @brief Copies the value of a resource of the same type.
    virtual void assign(const OwnedResource& other) = 0;
    virtual std::string bytes() const = 0;
    /// @brief Replaces the value from bytes(); throws std::runtime_error when they do not fit.
    virtual void load(std::string_view bytes) = 0;
    /// @brief Heap memory the value holds, for a type that reports it with a
    /// `std::size_t bytes() const` member (summary.json's memory per particle); else 0.
    virtual std::size_t memory() const = 0;

private:
    Lifetime m_lifetime;
};

template <class T>
class OwnedValue final : public OwnedResource {
public:
    /// Kept resources must become bytes (checkpoints); Scratch ones may be any copyable type.
    static constexpr bool serialisable = std::is_trivially_copyable_v<T> || SelfSerialising<T>;
    explicit OwnedValue(Lifetime lifetime) : OwnedResource(lifetime) {}
    T value{};
    const std::type_info& type() const override { return typeid(T); }
    std::size_t memory() const override {
        if constexpr (requires(const T& t) { { t.bytes() } -> std::convertible_to<std::size_t>; })
            return value.bytes();
        else
            return 0;
    }
    std::unique_ptr<OwnedResource> clone() const override { return std::make_unique<OwnedValue<T>>(*this); }
    void assign(const OwnedResource& other) override { value = static_cast<const OwnedValue<T>&>(other).value; }
    std::string bytes() const override {
        if constexpr (SelfSerialising<T>) {
            std::string out;
            value.save(out);
            return out;
        } else if constexpr (std::is_trivially_copyable_v<T>) {
            return std::string(reinterpret_cast<const char*>(&value), sizeof(T));
        } else {
            throw std::logic_error(std::string("a resource of type ") + typeid(T).name() + " has no byte form");
        }
    }
    void load(std::string_view in) override {
        if constexpr (SelfSerialising<T>) {
            value.load(in);
        } else if constexpr (!std::is_trivially_copyable_v<T>) {
            throw std::logic_error(std::string("a resource of type ") + typeid(T).name() + " has no byte form");
        } else {
            if (in.size() != sizeof(T))
                throw std::runtime_error("holds " + std::to_string(in.size()) + " bytes, this build's type has " +
                                         std::to_string(sizeof(T)));
            std::memcpy(&value, in.data(), sizeof(T));
        }
    }
};

/// @brief The owned resources of a world, by name.
class ResourceStore {
public:
    /// @brief Creates the resource (idempotent; the lifetime of the first call holds).
    template <class T>
    T& add(std::string_view name, Lifetime lifetime) {
        if (lifetime == Lifetime::Kept && !OwnedValue<T>::serialisable)
            throw std::logic_error("resource '" + std::string(name) +
                                   "' is Kept (checkpointed) but its type is neither trivially copyable nor has save()/load()");
        auto it = m_items.find(name);
        if (it == m_items.end()) it = m_items.emplace(std::string(name), std::make_unique<OwnedValue<T>>(lifetime)).first;
        return cast<T>(name, *it->second);
    }
    template <class T>
    T& get(std::string_view name) {
        return cast<T>(name, find(name));
    }
    template <class T>
    const T& get(std::string_view name) const {
        return cast<T>(name, const_cast<ResourceStore*>(this)->find(name));
    }
    bool has(std::string_view name) const { return m_items.find(name) != m_items.end(); }
    /// @brief Every resource, by name (checkpoints iterate the Kept ones).
    const std::map<std::string, std::unique_ptr<OwnedResource>, std::less<>>& items() const { return m_items; }
    OwnedResource& find(std::string_view name) {
        auto it = m_items.find(name);
        if (it == m_items.end()) throw std::logic_error("resource '" + std::string(name) + "' is not registered");
        return *it->second;
    }

    /// @brief A copy of the Kept resources (a rollback snapshot), reusing `out`'s storage.
    using Snapshot = std::map<std::string, std::unique_ptr<OwnedResource>, std::less<>>;
    void save(Snapshot& out) const;
    void restore(const Snapshot& in);

private:
    template <class T>
    static T& cast(std::string_view name, OwnedResource& r) {
        if (r.type() != typeid(T)) throw std::logic_error("resource '" + std::string(name) + "' has another type");
        return static_cast<OwnedValue<T>&>(r).value;
    }
    std::map<std::string, std::unique_ptr<OwnedResource>, std::less<>> m_items;
};

inline void ResourceStore::save(Snapshot& out) const {
    for (const auto& [name, r] : m_items) {
        if (r->lifetime() != Lifetime::Kept) continue;
        auto it = out.find(name);
        if (it == out.end())
            out.emplace(name, r->clone());
        else
            it->second->assign(*r);
    }
}

inline void ResourceStore::restore(const Snapshot& in) {
    for (const auto& [name, r] : in) find(name).assign(*r);
}

}  // namespace sph
