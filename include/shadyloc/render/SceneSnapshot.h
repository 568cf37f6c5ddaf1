/* ShadyLoc — offscreen snapshots of any MRPT 3D scene (mrpt::opengl::COpenGLScene)
 * to an image or a PNG, through mrpt::opengl::CFBORender (EGL/Mesa: no window
 * system, works on a headless machine). For MRPT applications that want a
 * picture of what they would show in a window: build the scene as for a
 * CDisplayWindow3D, then snapshot it. */
#pragma once

#include <mrpt/img/CImage.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/opengl/COpenGLScene.h>

#include <string>

namespace shadyloc::render
{
/** Where the snapshot's camera looks from (MRPT's orbit camera, CCamera). */
struct TSceneCamera
{
	/** Point at the centre of the main viewport's bounding box and set the
	 * zoom so that the whole box is in view (pointingAt and zoom_distance
	 * ignored). */
	bool auto_frame = true;
	mrpt::math::TPoint3D pointing_at{0, 0, 0};	//!< [m], when !auto_frame
	double zoom_distance = 10;	//!< eye distance from pointing_at [m], when !auto_frame
	double azimuth_deg = -90;  //!< about +z from +x [deg]; -90 with elevation 90: +x right, +y up the picture
	double elevation_deg = 90;	//!< above the xy plane [deg]; 90 = straight down
	bool orthographic = true;  //!< else perspective with fov_deg
	double fov_deg = 60;  //!< vertical field of view, perspective [deg]
};

/** The scene as seen by `cam` into an RGB image of width x height px.
 * Each call makes its own offscreen OpenGL context: the scene's shaders and
 * buffers are released before and after rendering (MRPT objects keep them
 * per context), so one scene can be snapshotted any number of times, and
 * shown in a window too (the window re-creates what it needs).
 * Throws std::runtime_error if the scene is empty under auto_frame or the
 * offscreen context cannot be made. */
mrpt::img::CImage snapshotScene(
	mrpt::opengl::COpenGLScene& scene, unsigned width, unsigned height, const TSceneCamera& cam = {});

/** The same, written to a PNG atomically (a temporary sibling, then renamed):
 * a failed render leaves no file. */
void snapshotSceneToPng(
	mrpt::opengl::COpenGLScene& scene, unsigned width, unsigned height, const std::string& pngPath,
	const TSceneCamera& cam = {});

/** An image written to a PNG atomically; throws naming the file. */
void writePngAtomically(const mrpt::img::CImage& img, const std::string& pngPath);

}  // namespace shadyloc::render
