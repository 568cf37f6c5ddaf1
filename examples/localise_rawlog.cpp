/* ShadyLoc example: an MRPT application that localises the colour stereo
 * frames of a rawlog against a keyframe map through <shadyloc/Localiser.h>
 * only (linking shadyloc::localisation, no simulator or evaluation code).
 * Reads the rawlog with MRPT's own reader, prints one line per frame, writes
 * the localised poses (map frame) as TUM and a top-down picture of the map
 * with them, rendered offscreen (no window system needed).
 *
 *   localise_rawlog MAP.kfmap LIVE.rawlog OUT CONFIG.ini [CONFIG.ini ...] [--frames N]
 *
 * writes OUT.tum and OUT.png. The configs are read as one text (the
 * project's ones are disjoint: config/vo_sim.ini + config/localise_sim.ini). */
#include <shadyloc/Localiser.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/format.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace
{
std::string readText(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw std::runtime_error("cannot read '" + path + "'");
	std::ostringstream s;
	s << f.rdbuf() << "\n";
	return s.str();
}

/** The map drawn in a z-up frame (the map's is the first keyframe's camera:
 * y down, z forward) with the localised positions over it, seen from above. */
void snapshot(const shadyloc::Localiser& loc, const std::vector<mrpt::poses::CPose3D>& poses, const std::string& png)
{
	auto zUp = mrpt::opengl::CSetOfObjects::Create();
	zUp->setPose(mrpt::poses::CPose3D::FromYawPitchRoll(0, 0, -M_PI / 2));
	loc.map().getVisualizationInto(*zUp);
	auto fixes = mrpt::opengl::CPointCloud::Create();
	fixes->setPointSize(6);
	fixes->setColor_u8(mrpt::img::TColor(220, 30, 30));
	for (const auto& p : poses) fixes->insertPoint(p.x(), p.y(), p.z());
	zUp->insert(fixes);
	mrpt::opengl::COpenGLScene scene;
	scene.insert(zUp);
	const auto bb = scene.getBoundingBox();
	mrpt::opengl::CFBORender render(800, 600);
	auto& cam = render.getCamera(scene);
	cam.setOrthogonal(true);
	cam.setElevationDegrees(90);
	cam.setAzimuthDegrees(-90);
	cam.setPointingAt((bb.min + bb.max) * 0.5);
	// MRPT 2.5's orthographic view spans half the zoom distance vertically.
	cam.setZoomDistance(float(2.2 * (bb.max - bb.min).norm()));
	mrpt::img::CImage img;
	render.render_RGB(scene, img);
	if (!img.saveToFile(png)) throw std::runtime_error("cannot write '" + png + "'");
}
}  // namespace

int main(int argc, char** argv)
try
{
	std::vector<std::string> args(argv + 1, argv + argc);
	size_t maxFrames = 0;  // 0: every frame
	if (args.size() >= 2 && args[args.size() - 2] == "--frames")
	{
		maxFrames = std::stoul(args.back());
		args.resize(args.size() - 2);
	}
	if (args.size() < 4)
	{
		std::cerr << "usage: localise_rawlog MAP.kfmap LIVE.rawlog OUT CONFIG.ini [CONFIG.ini ...] [--frames N]\n";
		return 2;
	}
	std::string ini;
	for (size_t i = 3; i < args.size(); i++) ini += readText(args[i]);
	shadyloc::LocaliserOptions opts;
	opts.loadFromConfigFile(mrpt::config::CConfigFileMemory(ini), "");
	shadyloc::Localiser loc(args[0], opts);

	mrpt::img::CImage::setImagesPathBase(mrpt::obs::CRawlog::detectImagesDirectory(args[1]));
	mrpt::io::CFileGZInputStream file(args[1]);
	auto arch = mrpt::serialization::archiveFrom(file);
	std::ofstream tum(args[2] + ".tum");
	std::vector<mrpt::poses::CPose3D> fixes;
	mrpt::obs::CActionCollection::Ptr acts;
	mrpt::obs::CSensoryFrame::Ptr sf;
	mrpt::obs::CObservation::Ptr obs;
	size_t entry = 0, frames = 0;
	while (maxFrames == 0 || frames < maxFrames)
	{
		sf.reset();	 // the reader sets either of them: a rawlog of sensory frames or of bare observations
		obs.reset();
		if (!mrpt::obs::CRawlog::getActionObservationPairOrObservation(arch, acts, sf, obs, entry)) break;
		std::vector<mrpt::obs::CObservation::Ptr> all = sf ? std::vector(sf->begin(), sf->end()) : std::vector{obs};
		for (const auto& o : all)
		{
			const auto r = loc.process(o);
			if (!r) continue;
			const auto& p = r->pose.mean;
			std::printf("frame %zu: %s (%s) kf %u quality %.2f  x %.3f y %.3f z %.3f\n", frames++,
						shadyloc::toString(r->status).c_str(), r->method.c_str(), r->keyframe_id, r->quality, p.x(),
						p.y(), p.z());
			if (r->status != shadyloc::LocalisationStatus::Localised) continue;
			mrpt::math::CQuaternionDouble q;
			p.getAsQuaternion(q);
			tum << mrpt::format("%.9f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", mrpt::Clock::toDouble(r->timestamp), p.x(),
								p.y(), p.z(), q.x(), q.y(), q.z(), q.r());
			fixes.push_back(p);
		}
	}
	snapshot(loc, fixes, args[2] + ".png");
	std::printf("%zu frames, %zu localised; wrote %s.tum and %s.png\n", frames, fixes.size(), args[2].c_str(),
				args[2].c_str());
	return 0;
}
catch (const std::exception& e)
{
	std::cerr << "localise_rawlog: " << e.what() << "\n";
	return 1;
}
