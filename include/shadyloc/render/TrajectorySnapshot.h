/* ShadyLoc — offscreen top-down snapshots of trajectories and 3D content such
 * as a keyframe map's drawing, through MRPT's 3D scene
 * (render/SceneSnapshot.h: CFBORender, EGL/Mesa, no window system needed). */
#pragma once

#include <mrpt/img/CImage.h>
#include <mrpt/img/TColor.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/opengl/CSetOfObjects.h>

#include <functional>
#include <utility>

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
	/** A square of this size [px] at every point (0: none), e.g. keyframes. */
	double markerPx = 0.0;
	mrpt::img::TColor markerColour{90, 90, 90};	 //!< of the squares
	/** Legend lines replacing the one "name" line, e.g. what each segment
	 * colour means. */
	std::vector<std::pair<std::string, mrpt::img::TColor>> legend;
};

/** 3D content under the paths, in the same frame as the trajectories' points:
 * e.g. a keyframe map's getVisualizationInto. Made once the view is known,
 * so that what is drawn as geometry (a ribbon) can be sized in pixels. */
struct TObjectLayer
{
	/** Legend lines: text and colour (e.g. the map, then its channels' landmarks). */
	std::vector<std::pair<std::string, mrpt::img::TColor>> legend;
	/** Points the view must include (e.g. the map's keyframe positions). */
	std::vector<mrpt::math::TPoint3D> extent;
	/** Makes the objects, given the picture's scale [m per px]. */
	std::function<mrpt::opengl::CSetOfObjects::Ptr(double metresPerPixel)> make;
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
	/** The legend lines under the title (off: the picture alone, e.g. a
	 * small frame captioned by its own means). */
	bool legend = true;
	/** Keep the band the title and legend take at the top free of content
	 * (the view frames the content in the rest of the picture). */
	bool legendBand = true;
};

/** Renders the object layers and, on top of them, the trajectory layers
 * top-down (orthographic) into a PNG written atomically, the view framing
 * every trajectory point and every object layer's extent, with a legend (the
 * trajectories, then the object layers) and a metric grid. Throws
 * std::runtime_error if there is nothing to draw or rendering fails. */
void renderTrajectories(
	const std::vector<TrajectoryLayer>& layers, const SnapshotOptions& opts, const std::string& pngPath,
	const std::vector<TObjectLayer>& objects = {});

/** The same picture as an image (e.g. a frame of an animation); `what`
 * names it in errors. */
mrpt::img::CImage renderTrajectoriesImage(
	const std::vector<TrajectoryLayer>& layers, const SnapshotOptions& opts, const std::vector<TObjectLayer>& objects,
	const std::string& what);

}  // namespace shadyloc::render
