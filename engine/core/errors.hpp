#pragma once
/// @file errors.hpp
/// @brief Typed errors: bad input (exit 2), a failed simulation (exit 3), an output the
/// environment would not take (exit 5).
#include <cstdint>
#include <stdexcept>
#include <string>

namespace sph {

/// @brief Bad input: a scene file, a command-line value or a resource file. Exit code 2.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// @brief A scene file that is malformed or out of range. The message names the file, the
/// JSON path, the value found and what was expected.
class SceneError : public InputError {
public:
    SceneError(std::string file, std::string json_path, std::string found, std::string expected);
    const std::string& file() const { return m_file; }
    const std::string& json_path() const { return m_path; }

private:
    std::string m_file, m_path;
};

/// @brief Writing an output failed for a reason outside the scene: the disk is full, a folder
/// is read-only, a path is too long for the file system. Exit code 5. The message names the
/// path and the operating system's reason.
class OutputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// @brief The simulation itself failed (NaN, particle outside the domain, step collapse).
/// Exit code 3. Names the particle, the step and the system that produced it.
class SimulationError : public std::runtime_error {
public:
    SimulationError(const std::string& what, std::int64_t particle, std::int64_t step,
                    std::string system)
        : std::runtime_error(what), m_particle(particle), m_step(step), m_system(std::move(system)) {}
    std::int64_t particle() const { return m_particle; }
    std::int64_t step() const { return m_step; }
    const std::string& system() const { return m_system; }

private:
    std::int64_t m_particle, m_step;
    std::string m_system;
};

}  // namespace sph

#ifdef SPH_ENABLE_ASSERTS
#include <cstdio>
#include <cstdlib>
/// Invariant check, active in debug and sanitizer builds.
#define SPH_ASSERT(cond, msg)                                                              \
    do {                                                                                   \
        if (!(cond)) {                                                                     \
            std::fprintf(stderr, "%s:%d: assertion '%s' failed: %s\n", __FILE__, __LINE__, \
                         #cond, msg);                                                      \
            std::abort();                                                                  \
        }                                                                                  \
    } while (0)
#else
#define SPH_ASSERT(cond, msg) ((void)0)
#endif
