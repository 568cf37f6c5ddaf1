/* ShadyLoc — offscreen top-down snapshots of trajectories through MRPT's 3D
 * scene (mrpt::opengl::CFBORender: EGL/Mesa, no window system needed). */
#pragma once

#include <mrpt/img/TColor.h>
#include <mrpt/math/TPoint3D.h>

#include <string>
#include <vector>

namespace shadyloc::render
{
/** One path in the picture. */
struct TrajectoryLayer
{
	std::string name;  //!< legend text
	std::vector<mrpt::math::TPoint3D> points;  //!< positions, metres
	mrpt::img::TColor colour{255, 0, 0};
	/** Optional colour per segment (size points-1), overriding `colour`:
	 * e.g. which localiser held each stretch of a run. */
	std::vector<mrpt::img::TColor> segmentColours;
	/** Ribbon width in pixels of the output image (the software renderer
	 * ignores line widths, so paths are drawn as triangle ribbons). */
	double widthPx = 4.0;
};

struct SnapshotOptions
{
	unsigned width = 1000;	//!< image width, px
	unsigned height = 800;	//!< image height, px
	/** Axis pointing "up" out of the picture: 'x', 'y', 'z', or 'a' (auto:
	 * the axis along which all points spread least, e.g. y for camera-frame
	 * trajectories of a ground vehicle). */
	char upAxis = 'a';
	double marginFraction = 0.08;  //!< empty border around the paths
	bool grid = true;  //!< a metric grid under the paths
	std::string title;	//!< text at the top left
};

/** Renders the layers top-down (orthographic) into a PNG written atomically.
 * Throws std::runtime_error if there is nothing to draw or rendering fails. */
void renderTrajectories(
	const std::vector<TrajectoryLayer>& layers, const SnapshotOptions& opts, const std::string& pngPath);

}  // namespace shadyloc::render
