/* ShadyLoc — a localisation run's output files (docs/localisation.md,
 * "Outputs"): frames.csv, solves.csv, trajectory.tum, summary.json and
 * timing.json, from the run's updates and their evaluation (Evaluation.h).
 * Written by `shadyloc localise` and by every pair job of the leave-one-out
 * evaluation, so a pair's files are exactly localise's; read back by the
 * commands that draw such folders (figures, render). The run itself is the
 * localisation library's (localisation::LocaliseRun), which writes nothing.
 */
#pragma once

#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/localisation/LocalisationSystem.h>

#include <string>
#include <vector>

namespace shadyloc::eval
{
/** summary.json's format version (docs/localisation.md). */
constexpr int kSummaryVersion = 1;

/** Where a run's inputs came from, for summary.json's provenance. */
struct TLocaliseProvenance
{
	std::string program = "shadyloc localise";
	std::string buildCommit = "unknown";  //!< the program's commit (written at build time; "-dirty" when built from modified sources)
	std::string configWhat, configText;	 //!< config names, their concatenated text (hashed)
	std::string mapPath, livePath, gtPath;	//!< as given; gtPath "" without ground truth
	std::string mapHash, liveHash, gtHash;	//!< io::fnv1a64File of each ("" = computed from the path)
	int startKf = -1;
	/** A live source (localise --live): frames read from it and dropped
	 * because the localiser was behind; absent for a rawlog. */
	bool live = false;
	size_t liveFramesRead = 0, liveFramesDropped = 0;
	bool liveDropsWhenBehind = false;  //!< a camera (or --realtime), not a file read at the localiser's pace
};

/** frames.csv: one row per live frame (docs/localisation.md). */
void writeFramesCsv(const std::string& path, const Updates& ups, const TEvaluation& ev, const CKeyframeMap& map);
/** solves.csv, the solve log: one row per localiser and frame with a solve,
 * accepted or not, with what the accept stage saw and, with ground truth,
 * its error and NEES (docs/localisation.md, "The solve log"). */
void writeSolvesCsv(const std::string& path, const Updates& ups, const TEvaluation& ev);
/** trajectory.tum: the live left camera in the map frame where a place is known. */
void writeTrajectory(const std::string& path, const Updates& ups);
/** summary.json's text (versioned; no times: it compares byte for byte). */
std::string summaryJson(
	const Updates& ups, const TEvaluation& ev, const localisation::TSystemOptions& sys, const TLocaliseProvenance& prov);
/** timing.json's text: per-frame times, median and 95th percentile. */
std::string timingJson(const Updates& ups, int threads);

/** A string of a localise output folder's provenance (summary.json's
 * "provenance": "map", "map_fnv1a64", "live", "live_fnv1a64", "gt",
 * "gt_fnv1a64", "localisers"); "" if absent (no summary.json, or not
 * JSON: an older or hand-made folder). For the commands that draw such
 * folders (figures, render). */
std::string localiseProvenance(const std::string& dir, const std::string& key);

/** All five files into folder `dir` (timing.json with sys.threads). */
void writeLocaliseOutputs(
	const std::string& dir, const Updates& ups, const TEvaluation& ev, const CKeyframeMap& map,
	const localisation::TSystemOptions& sys, const TLocaliseProvenance& prov);

}  // namespace shadyloc::eval
