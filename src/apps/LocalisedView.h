/* ShadyLoc — a localisation run drawn over its map, offscreen: the map's
 * keyframes and the live camera's
 * path in the map frame so far, each stretch coloured by who held it (the
 * monochrome localiser, the invariant one, or VO alone), with the latest
 * pose's heading. `shadyloc localise --view N` writes one every N frames;
 * `shadyloc render --localised` draws a finished run the same way. */
#pragma once

#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/render/TrajectorySnapshot.h>

#include <mrpt/img/TColor.h>

#include <string>
#include <vector>

namespace shadyloc::apps
{
/** Who held a frame, as every figure colours it (docs/figures.md). */
constexpr mrpt::img::TColor kMonoColour{31, 98, 196}, kInvariantColour{230, 130, 14}, kNoneColour{214, 39, 40};
/** The joint localiser's fixes (both channels in one solve). */
constexpr mrpt::img::TColor kJointColour{44, 160, 44};

/** The colour of a frame held by `used` ("mono", "invariant", "joint", "" = none). */
mrpt::img::TColor colourOfUsed(const std::string& used);

/** Frames counted by who held them, for a legend: mono, invariant, joint
 * (only where the joint localiser held any), then VO alone. */
class HolderTally
{
   public:
	struct TRow
	{
		std::string what;  //!< "mono fix", ..., "no fix (VO)"
		size_t frames = 0;
		mrpt::img::TColor colour;
	};
	void add(const std::string& used);
	std::vector<TRow> rows() const;
	size_t total() const { return m_mono + m_invariant + m_joint + m_none; }

   private:
	size_t m_mono = 0, m_invariant = 0, m_joint = 0, m_none = 0;
};

/** The map's keyframes as a grey band with a square each (the map's own
 * drawing is blue and orange, the localisers' colours here). */
render::TrajectoryLayer keyframesLayer(const CKeyframeMap& map, const std::string& name);

/** The name of frame `frame`'s picture in a --view folder: frame_NNNNNN.png. */
std::string viewFileName(size_t frame);

/** The layers of renderLocalisedView: the map's keyframes, the live path
 * coloured by who held it, the latest pose's heading. */
std::vector<render::TrajectoryLayer> localisedViewLayers(
	const CKeyframeMap& map, const std::vector<localisation::TLocalisationUpdate>& ups);

/** The live path of the updates so far where the place was known, and a
 * short arrow of the last pose's heading. Throws std::runtime_error (via
 * render::renderTrajectories) if there is nothing to draw; the PNG is written
 * atomically. */
void renderLocalisedView(
	const CKeyframeMap& map, const std::vector<localisation::TLocalisationUpdate>& ups, const render::SnapshotOptions& opts,
	const std::string& pngPath);

}  // namespace shadyloc::apps
