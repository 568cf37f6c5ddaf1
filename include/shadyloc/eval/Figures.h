/* ShadyLoc — the paper's Figures 7, 8 and 9 (McManus et al. 2014, Section IV)
 * as PNG, drawn headless by gnuplot (pngcairo terminal; Debian package
 * gnuplot-nox) from the per-frame outputs of `shadyloc localise`
 * (OUTDIR/frames.csv, docs/localisation.md). Definitions and examples:
 * docs/figures.md.
 *
 *  - Figure 7: one live run against one map: along the distance travelled,
 *    where the baseline run, the invariant localiser (of the combined run)
 *    and the combined run had a fix, over the frames outside the map;
 *  - Figure 8: one live run against several maps: a row per map, each
 *    stretch coloured by who had a fix there: baseline only, invariant only,
 *    both, neither ("baseline" is the baseline run, "invariant" the
 *    invariant localiser of the combined run);
 *  - Figure 9: P(an episode without a fix reaches a distance d) against d,
 *    baseline versus combined, over blind episodes between two fixes
 *    (eval/BlindEpisodes.h), with the episode counts.
 *
 * Every function writes its PNG atomically (nothing is left at the path on
 * an error) and throws std::runtime_error naming the file (and line) at
 * fault, or gnuplot's own message.
 */
#pragma once

#include <shadyloc/eval/BlindEpisodes.h>

#include <string>
#include <vector>

namespace shadyloc::eval
{

/** One row of a frames.csv: the columns the figures read. */
struct TLocalisedFrame
{
	int frame = 0;	//!< live frame index
	double stamp = 0;  //!< live timestamp [s]
	double distance_m = 0;	//!< travelled: gt_distance_m where the file has it, else distance_m (VO) [m]
	bool in_map = false;  //!< a map keyframe within 5 m / 30 deg (docs/localisation.md)
	int mono_ok = -1, invariant_ok = -1;  //!< 1 / 0: that localiser's fix accepted; -1: it did not run
	std::string used;  //!< mono, invariant or none
	int used_true = -1;	 //!< with ground truth: 1 true fix, 0 false fix; -1 unknown or no fix
	bool fix() const { return used != "none"; }
};

/** A frames.csv read whole. */
struct TLocalisedRun
{
	std::string path;
	/** distance_m of the frames comes from ground truth (the file has a
	 * gt_distance_m column: localise ran with --gt), else from VO. */
	bool gt_distance = false;
	std::vector<TLocalisedFrame> frames;
};

/** Reads `shadyloc localise`'s OUTDIR/frames.csv. Needs the columns frame,
 * stamp, distance_m, in_map, mono_ok, invariant_ok, used (others are
 * ignored; gt_distance_m and used_true are read when present). Throws
 * std::runtime_error naming the file and line: a missing column, a row with
 * another number of fields than the header, a value that is not a number
 * (or not 0/1, or not mono/invariant/none), no rows. */
TLocalisedRun readFramesCsv(const std::string& path);

/** The run's blind episodes, by the one definition (eval::blindEpisodes),
 * a fix being `used` != none and the distance that of the frames. */
std::vector<TBlindEpisode> blindEpisodesOf(const TLocalisedRun& run);

/** The lengths of the episodes between two fixes [m]: what Figure 9 and
 * summary.json's P(an episode reaches 100 m) count. */
std::vector<double> blindEpisodeLengths(const TLocalisedRun& run);

/** Who had a fix at a frame, from the baseline run and the combined run
 * (Figure 8's colours). */
enum class FixHolder
{
	Both,  //!< baseline run and the combined run's invariant localiser
	BaselineOnly,
	InvariantOnly,
	Neither
};
FixHolder fixHolder(const TLocalisedFrame& baseline, const TLocalisedFrame& combined);

/** One map of Figure 8: the live run against it, baseline and combined. */
struct TFigurePair
{
	std::string mapName;
	std::string baselineCsv;  //!< frames.csv of `localise --localisers mono`
	std::string combinedCsv;  //!< frames.csv of `localise` (mono,invariant)
};

/** Figure 7 of one live run against one map. The two files must be of the
 * same live run (same frames and stamps), else an error naming both. */
void figure7(
	const std::string& liveName, const std::string& mapName, const std::string& baselineCsv,
	const std::string& combinedCsv, const std::string& pngPath);

/** Figure 8 of one live run against each map of `pairs` (one row each, in
 * the order given). */
void figure8(const std::string& liveName, const std::vector<TFigurePair>& pairs, const std::string& pngPath);

/** Figure 9: P(a blind episode reaches d) for the baseline and the combined
 * episode lengths [m] (e.g. blindEpisodeLengths pooled over every pair),
 * linear axes, the counts and P(>= markAt_m) in the legend. Either set may
 * be empty (then its legend says so). `distanceFrom` names where the lengths
 * come from for the axis label ("ground truth", "VO"). */
void figure9(
	const std::vector<double>& baselineLengths_m, const std::vector<double>& combinedLengths_m,
	const std::string& pngPath, const std::string& distanceFrom = "ground truth", double markAt_m = 100.0);

/** gnuplot as a string literal: single-quoted, quotes doubled (the text is
 * shown as it is: the terminal is set noenhanced). */
std::string gnuplotQuote(const std::string& text);

/** Runs the gnuplot commands `body` with the pngcairo terminal of
 * width x height px writing `pngPath` (atomically: a temporary sibling,
 * renamed once gnuplot succeeded and wrote an image). Text is noenhanced
 * (run names keep their underscores). Throws std::runtime_error: gnuplot
 * missing (naming the Debian package), or its exit status and messages. */
void runGnuplot(const std::string& body, const std::string& pngPath, unsigned width, unsigned height);

}  // namespace shadyloc::eval
