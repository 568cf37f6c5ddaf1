/* ShadyLoc — what a leave-one-out job leaves for the merge (private to the
 * eval area): a map job's map.tsv and a pair job's pair.tsv, versioned text
 * ("key<TAB>values" lines, doubles with 17 significant digits so that the
 * merge computes from exactly the job's numbers). docs/evaluation.md. */
#pragma once

#include <shadyloc/eval/LeaveOneOut.h>
#include <shadyloc/eval/Evaluation.h>

#include <array>
#include <string>
#include <vector>

namespace shadyloc::eval
{
/** The accuracy bins of the long-term visual localisation benchmark
 * (Sattler et al., CVPR 2018): (m, deg). */
constexpr std::array<std::array<double, 2>, 3> kAccuracyBins = {{{0.25, 2.0}, {0.5, 5.0}, {5.0, 10.0}}};

struct TMapRecord
{
	std::string run;
	size_t frames = 0, keyframes = 0, gt_keyframes = 0, breaks = 0;
	double path_m = 0;
};

struct TPairChannel
{
	std::string name;
	size_t accepted = 0, used = 0, accepted_in_map = 0;
	size_t true_fixes = 0, true_in_map = 0, false_fixes = 0, unverifiable = 0;
};

struct TPairRecord
{
	std::string live, map, system, localisers;
	size_t frames = 0;
	bool ground_truth = false;
	size_t in_map_frames = 0, fixes = 0, fixes_in_map = 0;
	size_t true_fixes = 0, true_fixes_in_map = 0, false_fixes = 0, unverifiable = 0;
	double total_m = 0, blind_m = 0, before_first_fix_m = -1;
	int first_fix_frame = -1;
	size_t global_searches = 0;
	std::vector<TPairChannel> channels;
	std::array<size_t, 3> bins = {0, 0, 0};	 //!< in-map frames whose used fix is within kAccuracyBins[b]
	std::vector<std::array<double, 2>> fix_errors;	//!< (m, deg) of every used fix with ground truth
	std::vector<std::pair<std::string, double>> episodes;  //!< (kind, length [m])

	const TPairChannel* channel(const std::string& name) const;
};

TPairRecord makePairRecord(
	const std::string& live, const std::string& map, EvalSystem system,
	const Updates& ups, const TEvaluation& ev);

void writeMapRecord(const std::string& path, const TMapRecord& r);
TMapRecord readMapRecord(const std::string& path);
void writePairRecord(const std::string& path, const TPairRecord& r);
/** Throws std::runtime_error naming file and line. */
TPairRecord readPairRecord(const std::string& path);

}  // namespace shadyloc::eval
