#pragma once
/// @file run_folder.hpp
/// @brief An output folder owned by one run, so that the outputs of two runs never mix:
///   - a lock (flock on <dir>/.sph-run.lock) held for the run's life: a second run into the
///     same folder is refused while the first is alive;
///   - a marker, <dir>/run.json (run id, scene, pid, start time), naming the run whose outputs
///     the folder holds.
/// A fresh run into a folder that holds the outputs of an earlier marked run removes them
/// (stats.csv, summary.json, frames/, boundary/, the .pvd files, probes/, checkpoints/) when it
/// takes the folder, after its set-up succeeded (take()): a run whose set-up fails leaves the
/// earlier outputs as they were; the removal is all or nothing (an output that cannot be removed
/// leaves every one in place, but on a full disk, where they are deleted one by one). Outputs without a marker (another program's, or an older
/// sph-run's) are replaced only with `force`. A resumed run must find its own run's marker, or
/// a folder without outputs but checkpoints (or `force`; a checkpoint without a run id, from
/// before run ids, resumes into an unmarked folder as it always did).
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace sph {

class RunFolder {
public:
    /// @param run_id the run's identity (new_run_id() for a fresh run; a checkpoint's for a
    /// resumed one, "" for a checkpoint written before run ids existed)
    /// @param resume the run continues from a checkpoint (outputs are kept, see above)
    /// Throws InputError (a file where the folder should be, a name too long, a folder in use
    /// or holding another run's outputs) or OutputError (the folder cannot be created or
    /// written: the path and the operating system's reason), before anything is written.
    RunFolder(std::filesystem::path dir, std::string run_id, std::string scene, bool resume, bool force);
    ~RunFolder();
    RunFolder(const RunFolder&) = delete;
    RunFolder& operator=(const RunFolder&) = delete;

    /// @brief Set-up succeeded and the run is about to write: removes the earlier run's outputs
    /// the constructor found (see note()) and writes the marker. Throws OutputError when an
    /// output cannot be removed or the marker written. Called once; later calls do nothing.
    void take();
    /// @brief The run has begun writing: the folder is kept whatever happens next. Until
    /// then a folder this object created is removed again when it is destroyed (a run whose
    /// set-up failed leaves nothing behind).
    void keep() { m_keep = true; }
    const std::filesystem::path& dir() const { return m_dir; }
    const std::string& run_id() const { return m_run_id; }
    /// @brief Whether take() removes (removed) an earlier run's outputs (a fresh run's, or with
    /// `force` another's): a resume then checks nothing of theirs.
    bool replaces() const { return m_replace != Replace::None; }
    /// @brief What take() does (did) with earlier outputs, for the log ("" when nothing).
    const std::string& note() const { return m_note; }

private:
    std::filesystem::path m_dir, m_created_root;
    std::string m_run_id, m_note;
    int m_lock_fd = -1;
    bool m_created = false, m_keep = false, m_taken = false;
    enum class Replace { None, All, AllButCheckpoints } m_replace = Replace::None;
    nlohmann::json m_marker;  ///< written by take()
};

/// @brief A new run identity: 16 hexadecimal digits from the system's random source.
std::string new_run_id();

}  // namespace sph
