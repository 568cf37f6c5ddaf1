/* ShadyLoc — blind episodes of a localisation run (McManus et al. 2014,
 * Section IV and Figure 9; definition in docs/localisation.md): the one
 * definition, used by eval::evaluate on a run in memory and by the
 * figures on a run's frames.csv (eval/Figures.h). */
#pragma once

#include <cstddef>
#include <vector>

namespace shadyloc::eval
{
/** A maximal run of frames without a fix. */
struct TBlindEpisode
{
	size_t first = 0, last = 0;	 //!< frames without a fix (indices)
	double length_m = 0;  //!< from the fix before to the fix after (or the run's end) [m]
	enum Kind
	{
		Between,  //!< between two fixes: a failure and its recovery
		BeforeFirstFix,	 //!< from the run's start (a run never localised is one of these)
		AtEnd  //!< after the last fix to the run's end
	} kind = Between;
};

/** A kind as the outputs name it: "between", "before_first_fix", "at_end". */
const char* toString(TBlindEpisode::Kind k);

/** The blind episodes of a run: `fix[i]` tells whether frame i has a fix,
 * `distance_m[i]` is the distance travelled up to frame i [m] (ground
 * truth's where given, else VO's). An episode's length runs from the fix
 * before it to the fix after it; the stretch before the first fix is
 * measured from frame 0 and the one after the last fix to the last frame.
 * Throws std::invalid_argument if the two vectors differ in size. */
std::vector<TBlindEpisode> blindEpisodes(const std::vector<bool>& fix, const std::vector<double>& distance_m);

}  // namespace shadyloc::eval
