/* ShadyLoc — offscreen snapshots of MRPT scenes. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/render/SceneSnapshot.h>

#include <mrpt/opengl/CFBORender.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shadyloc::render
{
mrpt::img::CImage snapshotScene(
	mrpt::opengl::COpenGLScene& scene, unsigned width, unsigned height, const TSceneCamera& c)
{
	if (width == 0 || height == 0) throw std::invalid_argument("snapshotScene: image size must be > 0");
	mrpt::opengl::CFBORender render(width, height);
	auto& cam = render.getCamera(scene);
	cam.setOrthogonal(c.orthographic);
	if (!c.orthographic) cam.setProjectiveFOVdeg(float(c.fov_deg));
	cam.setAzimuthDegrees(float(c.azimuth_deg));
	cam.setElevationDegrees(float(c.elevation_deg));
	size_t objects = 0;
	scene.visitAllObjects([&](const mrpt::opengl::CRenderizable::Ptr&) { objects++; });
	if (c.auto_frame)
	{
		if (objects == 0) throw std::runtime_error("snapshotScene: the scene is empty (nothing to frame)");
		const auto bb = scene.getBoundingBox();
		const auto d = bb.max - bb.min;
		if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z) || bb.min.x > bb.max.x)
			throw std::runtime_error("snapshotScene: the scene is empty (no bounding box to frame)");
		cam.setPointingAt((bb.min + bb.max) * 0.5);
		// The box fits inside a sphere of this radius whatever the view direction.
		const double r = std::max(0.5 * d.norm(), 1e-3);
		const double aspect = double(width) / height;
		if (c.orthographic)
			// MRPT 2.5 shows a vertical extent of half the zoom distance in
			// orthographic mode (measured, render/TrajectorySnapshot.cpp).
			cam.setZoomDistance(float(2.0 * 2 * r * std::max(1.0, 1.0 / aspect) * 1.05));
		else
		{
			const double half = 0.5 * c.fov_deg * M_PI / 180;
			cam.setZoomDistance(float(1.05 * r / std::sin(std::min(half, half * aspect))));
		}
	}
	else
	{
		cam.setPointingAt(c.pointing_at);
		cam.setZoomDistance(float(c.zoom_distance));
	}
	// GL names held by the objects belong to the context that made them:
	// drop any from an earlier context, and ours once done.
	scene.unloadShaders();
	scene.freeOpenGLResources();
	scene.visitAllObjects([](const mrpt::opengl::CRenderizable::Ptr& o) { o->notifyChange(); });
	mrpt::img::CImage img;
	try
	{
		render.render_RGB(scene, img);
	}
	catch (...)
	{
		scene.unloadShaders();
		scene.freeOpenGLResources();
		throw;
	}
	scene.unloadShaders();
	scene.freeOpenGLResources();
	return img;
}

void snapshotSceneToPng(
	mrpt::opengl::COpenGLScene& scene, unsigned width, unsigned height, const std::string& pngPath,
	const TSceneCamera& cam)
{
	writePngAtomically(snapshotScene(scene, width, height, cam), pngPath);
}

void writePngAtomically(const mrpt::img::CImage& img, const std::string& pngPath)
{
	io::writeAtomically(pngPath, [&](const std::string& tmp) {
		if (!img.saveToFile(tmp)) throw std::runtime_error("'" + pngPath + "': cannot write PNG");
	});
}

}  // namespace shadyloc::render
