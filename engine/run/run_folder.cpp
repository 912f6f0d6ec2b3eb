#include "engine/run/run_folder.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <climits>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/core/errors.hpp"
#include "engine/run/io.hpp"

namespace sph {

namespace {

namespace fs = std::filesystem;

constexpr const char* kMarker = "run.json";
constexpr const char* kLock = ".sph-run.lock";
constexpr const char* kReplaced = ".sph-replaced";  ///< prefix of the folders an earlier run's outputs leave by
/// What sph-run writes into its folder (and so may remove again).
constexpr const char* kOutputs[] = {"scene_as_run.json", "stats.csv", "summary.json", "frames", "frames.pvd", "boundary",
                                    "boundary_moving.pvd", "probes", "checkpoints", "surface", ".sph-reserve"};

/// The outputs found in dir, comma-separated; `written_only`: not counting checkpoints/ and the
/// reserve (what a resume would append to or list).
std::string list_outputs(const fs::path& dir, bool written_only = false) {
    std::string found;
    for (const char* o : kOutputs) {
        if (written_only && (std::strcmp(o, "checkpoints") == 0 || std::strcmp(o, ".sph-reserve") == 0)) continue;
        std::error_code ec;
        if (fs::exists(dir / o, ec)) found += (found.empty() ? "" : ", ") + std::string(o);
    }
    return found;
}

/// Removes the outputs all or nothing: each is first renamed into a hidden folder of this run's,
/// `.sph-replaced-<run id>` (a rename happens whole or not at all); when one cannot be (a folder
/// without write permission, a mount point), those already moved are put back and OutputError
/// names it and says which, if any, could not be put back. Only then is the hidden folder deleted;
/// what cannot be deleted stays there, out of the new run's way, and the next replacement tries
/// again to delete every such folder. Where the hidden folder cannot be made because the disk is
/// full (ENOSPC, EDQUOT), the outputs are deleted one by one instead, which frees the room.
void remove_outputs(const fs::path& dir, const std::string& run_id, bool keep_checkpoints) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))  // earlier replacements' leftovers
        if (e.path().filename().native().starts_with(kReplaced)) fs::remove_all(e.path(), ec);
    const fs::path trash = dir / (std::string(kReplaced) + "-" + (run_id.empty() ? std::string("run") : run_id));
    ec.clear();
    fs::create_directory(trash, ec);
    const bool no_room = ec == std::errc::no_space_on_device || ec.value() == EDQUOT;
    if (ec && !no_room)
        throw OutputError(trash.string() + ": cannot create it to replace the earlier run's outputs (" + ec.message() + ")");
    std::vector<const char*> moved;
    for (const char* o : kOutputs) {
        if (keep_checkpoints && std::strcmp(o, "checkpoints") == 0) continue;
        if (!fs::exists(fs::symlink_status(dir / o, ec))) continue;
        if (no_room) {
            fs::remove_all(dir / o, ec);
            if (ec) throw OutputError((dir / o).string() + ": cannot remove the earlier run's output (" + ec.message() + ")");
            continue;
        }
        fs::rename(dir / o, trash / o, ec);
        if (ec) {
            std::string why = ec.message(), stranded;
            for (auto it = moved.rbegin(); it != moved.rend(); ++it) {
                fs::rename(trash / *it, dir / *it, ec);
                if (ec) stranded += (stranded.empty() ? "" : ", ") + std::string(*it);
            }
            if (stranded.empty()) fs::remove(trash, ec);
            throw OutputError((dir / o).string() + ": cannot remove the earlier run's output (" + why + "); " +
                              (stranded.empty() ? std::string("none of its outputs was removed")
                                                : "the others are in place but " + stranded + ", which could not be put back, in " +
                                                      trash.string()));
        }
        moved.push_back(o);
    }
    if (!no_room) fs::remove_all(trash, ec);
}

nlohmann::json read_marker(const fs::path& dir) {
    std::ifstream in(dir / kMarker);
    if (!in) return nullptr;
    try {
        nlohmann::json j = nlohmann::json::parse(in);
        if (j.is_object() && j.contains("run_id") && j["run_id"].is_string()) return j;
    } catch (const nlohmann::json::exception&) {
    }
    return nullptr;
}

std::string describe(const nlohmann::json& marker) {
    std::string s = "run " + marker["run_id"].get<std::string>();
    if (marker.contains("scene") && marker["scene"].is_string()) s += " of scene '" + marker["scene"].get<std::string>() + "'";
    return s;
}

}  // namespace

std::string new_run_id() {
    std::random_device rd;
    const std::uint64_t a = (std::uint64_t(rd()) << 32) ^ rd() ^
                            std::uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(a));
    return buf;
}

RunFolder::RunFolder(fs::path dir, std::string run_id, std::string scene, bool resume, bool force)
    : m_dir(std::move(dir)), m_run_id(std::move(run_id)) {
    // Checked before anything is created: a name the file system cannot hold.
    for (const auto& part : m_dir)
        if (part.native().size() > NAME_MAX)
            throw InputError(m_dir.string() + ": the folder name '" + part.native().substr(0, 40) + "...' is " +
                             std::to_string(part.native().size()) + " bytes, more than the file system's " +
                             std::to_string(NAME_MAX) + " (a shorter scene \"name\" or --out)");
    std::error_code ec;
    const auto st = fs::status(m_dir, ec);
    if (fs::exists(st) && !fs::is_directory(st))
        throw InputError(m_dir.string() + ": is a file, expected a folder for the outputs (or a path that does not exist yet)");
    m_created = !fs::exists(st);
    if (m_created) {  // the outermost folder this run creates: removed again if set-up fails
        m_created_root = m_dir;
        for (fs::path p = m_dir.parent_path(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) m_created_root = p;
    }
    fs::create_directories(m_dir, ec);
    if (ec) throw OutputError(m_dir.string() + ": cannot create the output folder (" + ec.message() + ")");
    m_lock_fd = ::open((m_dir / kLock).c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (m_lock_fd < 0) {
        const std::string why = std::strerror(errno);
        if (m_created) fs::remove_all(m_created_root, ec);
        throw OutputError(m_dir.string() + ": cannot write in the output folder (" + why + ")");
    }
    const nlohmann::json marker = read_marker(m_dir);
    if (::flock(m_lock_fd, LOCK_EX | LOCK_NB) != 0) {
        ::close(m_lock_fd);
        m_lock_fd = -1;
        std::string who = "another sph-run";
        if (!marker.is_null() && marker.contains("pid") && marker["pid"].is_number())
            who += " (pid " + std::to_string(marker["pid"].get<long long>()) + ", " + describe(marker) + ")";
        throw InputError(m_dir.string() + ": " + who + " is writing to this folder; wait for it or choose another --out");
    }
    // A run killed between naming a finished file and renaming it onto its target (the moment
    // AtomicFile::commit needs) leaves that hidden temporary; the folder is ours now (locked), so
    // no live writer owns one: remove them.
    for (const char* sub : {"", "frames", "boundary", "probes", "checkpoints", "surface"}) {
        for (const auto& e : fs::directory_iterator(m_dir / sub, ec))
            if (e.path().filename().native().starts_with(".sph.tmp")) fs::remove(e.path(), ec);
        ec.clear();
    }
    const std::string outputs = list_outputs(m_dir);
    try {
        if (!resume) {
            if (!outputs.empty()) {
                if (marker.is_null() && !force)
                    throw InputError(m_dir.string() + ": holds outputs (" + outputs +
                                     ") that no sph-run run claims (no run.json); pass --force to replace them or "
                                     "choose another --out");
                m_replace = Replace::All;
                m_note = "replaced the outputs (" + outputs + ") of " +
                         (marker.is_null() ? std::string("an unmarked run") : describe(marker)) + " in " + m_dir.string();
            }
        } else if (marker.is_null() && !m_run_id.empty() && !list_outputs(m_dir, true).empty()) {
            // Outputs no run claims: continuing the checkpoint's run here would append to (and
            // list in frames.pvd) another run's files.
            if (!force)
                throw InputError(m_dir.string() + ": holds outputs (" + outputs +
                                 ") that no sph-run run claims (no run.json), the checkpoint belongs to run " +
                                 (m_run_id.empty() ? std::string("(unnamed)") : m_run_id) +
                                 "; resume into the run's own folder or an empty --out, or pass --force to replace them");
            m_replace = Replace::AllButCheckpoints;
            m_note = "replaced the outputs (" + outputs + ") of an unmarked run in " + m_dir.string();
        } else if (!marker.is_null() && marker["run_id"].get<std::string>() != m_run_id && !m_run_id.empty()) {
            if (!force)
                throw InputError(m_dir.string() + ": holds the outputs of " + describe(marker) +
                                 ", the checkpoint belongs to run " + m_run_id +
                                 "; resume into the run's own folder or an empty --out, or pass --force to replace them");
            m_replace = Replace::AllButCheckpoints;  // the checkpoint being resumed may live in checkpoints/
            m_note = "replaced the outputs of " + describe(marker) + " in " + m_dir.string();
        }
        m_marker = {{"run_id", m_run_id},
                    {"scene", scene},
                    {"pid", ::getpid()},
                    {"resumed", resume},
                    {"sph_version", SPH_VERSION}};
        // A folder this run created holds no earlier outputs: marked now, so that a second run
        // started during the set-up sees whose it is.
        if (m_created) take();
    } catch (...) {
        ::close(m_lock_fd);
        m_lock_fd = -1;
        if (m_created) fs::remove_all(m_created_root, ec);
        throw;
    }
}

void RunFolder::take() {
    if (m_taken) return;
    if (m_replace != Replace::None) remove_outputs(m_dir, m_run_id, m_replace == Replace::AllButCheckpoints);
    m_marker["started_unix_s"] =
        std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
    write_file_atomic(m_dir / kMarker, m_marker.dump(2) + "\n");
    m_taken = true;
}

RunFolder::~RunFolder() {
    if (m_created && !m_keep) {  // set-up failed before the run wrote anything: leave nothing
        std::error_code ec;
        fs::remove(m_dir / kMarker, ec);
        fs::remove(m_dir / kLock, ec);
        // Each folder it created, innermost first, and only while empty.
        for (fs::path p = m_dir; !p.empty(); p = p.parent_path()) {
            if (!fs::remove(p, ec) || p == m_created_root) break;
        }
    }
    if (m_lock_fd >= 0) ::close(m_lock_fd);
}

}  // namespace sph
