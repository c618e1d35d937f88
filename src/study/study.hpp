#pragma once
/// \file `crackle study scene.yaml -o DIR`: runs every case of a parameter study (plan.hpp) as its
/// own `crackle` process, in parallel, resumably, and tabulates the results.
///
/// Layout of DIR:
/// - `cases/NNNN/`: `scene.yaml` (the full case scene), the case command's outputs (modal.json,
///   spectrum.json, ...), `log.txt` (the commands' stderr), `stdout.txt`, and `case.json`, written
///   last and atomically: a case is done exactly when its case.json exists with the hash of its
///   scene and outputs. A rerun skips done cases (failed ones too, unless retry_failed) and redoes
///   the rest, so an interrupted study (Ctrl-C, kill -9) loses at most the cases in flight.
/// - `modal-cache/KEY/`: shared uncracked modes of the cases with modal cache key KEY, filled by a
///   primer run (`crackle modal primer.yaml -o KEY/primer --modal-cache KEY`) before those cases.
/// - `study.csv`: one row per case, identical for identical results (no timings);
///   `study.json`: the same plus each case's wall time; `plots/`: PNGs of every damage index and
///   first-mode frequency against each varied key.
///
/// Under an MPI launcher (OMPI_COMM_WORLD_SIZE/RANK, or PMI_SIZE/RANK) rank r runs the cases
/// i with i % N == r; rank 0 then waits until every case is done (it watches the case.json files)
/// and writes the tables.
#include <iosfwd>
#include <string>

namespace crackle::study {

struct StudyOptions {
  std::string scene_path;  ///< scene file with a `study:` section
  std::string output_dir;  ///< DIR
  /// crackle executable run per case, as `EXE modal|run CASE/scene.yaml -o CASE [--modal-cache C]`
  /// (the app passes /proc/self/exe).
  std::string executable;
  int jobs = 0;               ///< cases at a time per rank; 0: the cores (shared among the node's ranks)
  bool modal_cache = true;    ///< pass --modal-cache to the case commands and prime each key once
  /// With modal_cache: one cache folder for every case instead of one per modal cache key (no
  /// primers). Its entries are keyed by content (modal/cache.hpp), so the cases of several studies
  /// given the same folder read each other's solves (crackle plan's sweeps read its modal batch's).
  std::string modal_cache_directory;
  bool retry_failed = false;  ///< rerun cases recorded as failed
  bool progress = true;       ///< the progress lines (cases done, running, ETA) on the log
  double case_timeout_s = 0;  ///< stop a case after this long (recorded as failed); 0: no limit
  /// OMP_NUM_THREADS and OPENBLAS_NUM_THREADS of the case processes where the environment does not
  /// set them; 0: leave unset.
  int threads_per_case = 1;
  std::string gnuplot = "gnuplot";  ///< for the plots; a missing gnuplot skips them with a note; empty: no plots
  int rank = -1;                    ///< this process's rank; -1: from the MPI launcher's environment (else 0)
  int n_ranks = -1;                 ///< number of ranks; -1: from the environment (else 1)
  double poll_interval_s = 0.05;    ///< how often running cases are checked
};

/// Exit code of a study whose cases are all done but some failed (`crackle study` exits with it).
constexpr int kExitFailedCases = 3;

/// Runs the study; progress (cases done/total, failures, ETA) and notes go to `log`. A failed case
/// does not stop the others: it is recorded (case.json `error`: the `crackle: error: ...` line of
/// its stderr) and tabulated. Returns 0 when every case is done and ok, kExitFailedCases (3) when
/// every case is done and at least one failed (this run or an earlier one; on rank 0, which
/// writes the tables; other ranks return 0 so that the MPI launcher lets rank 0 finish), 130
/// when interrupted by SIGINT/SIGTERM/SIGHUP (the cases in flight are stopped and not recorded).
/// Throws InputError (exit code 2), before any case runs, for a bad scene or study section or a
/// case the scene loader rejects; IoError when DIR cannot be written or is in use by another study.
int run_study(const StudyOptions& options, std::ostream& log);

}  // namespace crackle::study
