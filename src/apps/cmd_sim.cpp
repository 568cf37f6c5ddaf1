/* shadyloc sim: render stereo traversals of the simulated route as rawlogs
 * with ground truth, and optional contact sheets to look at them. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/sim/StereoSimulator.h>

#include <mrpt/system/string_utils.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <set>

namespace fs = std::filesystem;

namespace cmd_sim
{
/** Collects a few frames of one traversal and lays them out on one image. */
class ContactSheet
{
   public:
	ContactSheet(int frames, int tiles, double scale, const shadyloc::sim::TSimCameraOptions& cam)
		: m_cam(cam), m_scale(scale)
	{
		for (int j = 0; j < tiles; j++)
			m_pick.insert(tiles == 1 ? 0 : static_cast<int>(std::lround(j * (frames - 1.0) / (tiles - 1))));
		m_mid = *std::next(m_pick.begin(), static_cast<long>(m_pick.size() / 2));
	}
	void add(const shadyloc::sim::TSimFrame& f)
	{
		if (!m_pick.count(f.index)) return;
		char s[64];
		std::snprintf(s, sizeof(s), "left #%d  s=%.0f m", f.index, f.route_s_m);
		m_tiles.push_back(label(half(f.left), s));
		if (f.index != m_mid) return;
		cv::Mat mono, inv, grey3, inv3;
		shadyloc::image::toMonochrome(f.left, mono, shadyloc::image::ChannelOrder::BGR);
		const auto p = shadyloc::image::InvariantParams::FromWavelengths(
			m_cam.spectral.peak_nm[0], m_cam.spectral.peak_nm[1], m_cam.spectral.peak_nm[2]);
		shadyloc::image::InvariantTransform(p).apply(f.left, inv);
		cv::cvtColor(mono, grey3, cv::COLOR_GRAY2BGR);
		cv::cvtColor(inv, inv3, cv::COLOR_GRAY2BGR);
		m_extra = {label(half(f.right), "right #" + std::to_string(f.index)),
				   label(half(grey3), "mono #" + std::to_string(f.index)),
				   label(half(inv3), "invariant #" + std::to_string(f.index))};
	}
	/** Writes the sheet to `tmp` (the transaction's temporary for `path`). */
	void write(const std::string& tmp, const std::string& path, const std::string& title) const
	{
		std::vector<cv::Mat> all = m_tiles;
		all.insert(all.end(), m_extra.begin(), m_extra.end());
		if (all.empty()) return;
		const int cols = 3, w = all[0].cols, h = all[0].rows;
		const int rows = static_cast<int>((all.size() + cols - 1) / cols);
		cv::Mat sheet(rows * h + 22, cols * w, CV_8UC3, cv::Scalar(30, 30, 30));
		cv::putText(sheet, title, {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.42, {255, 255, 255}, 1, cv::LINE_AA);
		for (size_t i = 0; i < all.size(); i++)
			all[i].copyTo(sheet(cv::Rect(static_cast<int>(i % cols) * w, 22 + static_cast<int>(i / cols) * h, w, h)));
		if (!cv::imwrite(tmp, sheet, {cv::IMWRITE_PNG_COMPRESSION, 9}))
			throw std::runtime_error("'" + path + "': cannot write contact sheet");
		std::cout << "contact sheet: " << path << "\n";
	}

   private:
	cv::Mat half(const cv::Mat& m) const
	{
		cv::Mat out;
		cv::resize(m, out, cv::Size(), m_scale, m_scale, cv::INTER_AREA);
		return out;
	}
	static cv::Mat label(cv::Mat m, const std::string& s)
	{
		cv::putText(m, s, {4, 12}, cv::FONT_HERSHEY_SIMPLEX, 0.35, {0, 0, 0}, 2, cv::LINE_AA);
		cv::putText(m, s, {4, 12}, cv::FONT_HERSHEY_SIMPLEX, 0.35, {255, 255, 255}, 1, cv::LINE_AA);
		return m;
	}
	const shadyloc::sim::TSimCameraOptions& m_cam;
	double m_scale = 0.5;
	std::set<int> m_pick;
	int m_mid = 0;
	std::vector<cv::Mat> m_tiles, m_extra;
};

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Renders colour stereo traversals of one simulated outdoor route under different lighting "
		"(spectral sun + sky model, ray-cast shadows, dappled canopy light) as rawlogs: "
		"OUTDIR/<traversal>.rawlog (CObservationStereoImages 'CAMERA', linear BGR) and "
		"OUTDIR/<traversal>.tum (ground truth: left camera in the world).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> cfg("c", "config", "simulator .ini (see config/sim.ini)", true, "", "sim.ini", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output directory (created if missing)", true, "", "dir", cmd);
	shadyloc::apps::NumberArg<int> frames(
		cli, "", "frames", "frames per traversal, >= 1 (default: the .ini's frames or end_s_m)", -1, "N", 1, 10000000);
	TCLAP::ValueArg<std::string> which(
		"", "traversals", "comma-separated traversal names (default: all in [sim] traversals)", false, "", "a,b", cmd);
	TCLAP::ValueArg<std::string> sheet(
		"", "contact-sheet", "also write <PREFIX><traversal>.png: a few left frames, right/mono/invariant of one",
		false, "", "PREFIX", cmd);
	shadyloc::apps::NumberArg<int> tiles(cli, "", "sheet-frames", "left frames per contact sheet, 1..30", 6, "N", 1, 30);
	shadyloc::apps::NumberArg<double> sheetScale(
		cli, "", "sheet-scale", "contact sheet tile size / image size, in [0.05, 1]", 0.375, "f", 0.05, 1.0);
	shadyloc::apps::NumberArg<double> startS(
		cli, "", "start-s", "route position of the first frame, m (default: each traversal's start_s_m)", 0, "m");
	shadyloc::apps::NumberArg<double> endS(cli, "", "end-s",
		"end every traversal at its first frame at or past this route position, m (instead of a frame count; "
		"default: the .ini's frames or end_s_m)",
		0, "m");
	TCLAP::SwitchArg dump("", "dump-options", "print the effective options and exit", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no progress output", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	const auto opts = shadyloc::sim::TSimOptions::FromFile(cfg.getValue());
	if (dump.getValue())
	{
		opts.dumpToTextStream(std::cout);
		return 0;
	}
	if (!quiet.getValue())
	{
		std::cout << "Simulator options (" << cfg.getValue() << "):\n";
		opts.dumpToTextStream(std::cout);
		std::cout << "\n";
	}
	// Resolve every name before rendering anything: no partial dataset.
	std::vector<shadyloc::sim::TTraversal> todo;
	if (which.isSet())
	{
		std::vector<std::string> names;
		mrpt::system::tokenize(which.getValue(), ", ", names);
		if (names.empty()) throw std::invalid_argument("--traversals: empty list");
		for (const auto& n : names) todo.push_back(opts.traversal(n));
	}
	else
		todo = opts.traversals;
	if (frames.isSet() && endS.isSet()) throw std::invalid_argument("--frames and --end-s: give one, not both");
	// Overrides apply to the traversal copies, which are then checked again;
	// every frame count is known before anything is rendered.
	for (auto& t : todo)
	{
		if (startS.isSet()) t.start_s_m = startS.getValue();
		if (frames.isSet()) t.frames = frames.getValue();
		if (endS.isSet())
		{
			t.frames = 0;
			t.end_s_m = endS.getValue();
		}
		try
		{
			opts.validateTraversal(t);
		}
		catch (const std::invalid_argument& e)
		{
			throw std::invalid_argument(std::string(e.what()) + (startS.isSet() || endS.isSet() || frames.isSet()
																	 ? " (after --start-s/--end-s/--frames)"
																	 : ""));
		}
	}

	const fs::path dir(out.getValue());
	std::error_code ec;
	// Every rawlog, ground truth and contact sheet is put in place together
	// at the end, or none is; a folder made here goes again on failure.
	const bool made = !fs::exists(dir, ec);
	fs::create_directories(dir, ec);
	if (!fs::is_directory(dir)) throw std::runtime_error("'" + dir.string() + "': cannot create output directory");
	struct RemoveIfMade
	{
		fs::path dir;
		bool armed;
		~RemoveIfMade()
		{
			std::error_code e;
			if (armed) fs::remove(dir, e);	// only if left empty
		}
	} removeIfMade{dir, made};
	shadyloc::io::OutputTransaction outputs;
	outputs.addInput(cfg.getValue(), "simulator config");
	std::vector<std::string> sheetTmps;
	if (sheet.isSet())
		for (const auto& t : todo)
		{
			const std::string path = sheet.getValue() + t.name + ".png";
			sheetTmps.push_back(outputs.addFile(path, "contact sheet"));
			shadyloc::io::checkImageWritable(path);
		}

	shadyloc::sim::StereoSimulator sim(opts);
	sim.setMinLoggingLevel(quiet.getValue() ? mrpt::system::LVL_WARN : mrpt::system::LVL_INFO);
	std::vector<int> counts;
	for (const auto& t : todo)
	{
		sim.setTraversal(t);
		counts.push_back(sim.frameCount());
		if (!quiet.getValue())
		{
			char line[256];
			std::snprintf(line, sizeof(line), "%-22s %5d frames, route s = %.1f .. %.1f m\n", t.name.c_str(),
				counts.back(), sim.routePosition(0), sim.routePosition(counts.back() - 1));
			std::cout << line;
		}
	}
	const auto t0 = std::chrono::steady_clock::now();
	int total = 0;
	for (const auto& t : todo)
	{
		sim.setTraversal(t);
		const int n = counts[static_cast<size_t>(&t - todo.data())];
		ContactSheet cs(n, tiles.getValue(), sheetScale.getValue(), opts.camera);
		if (!quiet.getValue())
			std::cout << "[" << (&t - todo.data()) + 1 << "/" << todo.size() << "] " << t.name << ": " << n
					  << " frames\n"
					  << std::flush;
		sim.generate((dir / (t.name + ".rawlog")).string(), (dir / (t.name + ".tum")).string(), n,
			[&](const shadyloc::sim::TSimFrame& f) {
				if (sheet.isSet()) cs.add(f);
			},
			&outputs);
		total += n;
		if (sheet.isSet())
		{
			char title[256];
			if (t.overcast)
				std::snprintf(title, sizeof(title), "%s: overcast, sky %.0f K, sigma %.0f nm", t.name.c_str(),
					t.sky_temperature_K, opts.camera.spectral.sigma_nm);
			else
				std::snprintf(title, sizeof(title), "%s: sun az %.0f el %.0f, %.0f K, sky %.0f K, sigma %.0f nm",
					t.name.c_str(), t.sun_azimuth_deg, t.sun_elevation_deg, t.sun_temperature_K,
					t.sky_temperature_K, opts.camera.spectral.sigma_nm);
			cs.write(sheetTmps[static_cast<size_t>(&t - todo.data())], sheet.getValue() + t.name + ".png", title);
		}
	}
	outputs.commit();
	removeIfMade.armed = false;
	const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	if (!quiet.getValue())
		std::cout << "sim: " << todo.size() << " traversal(s), " << total << " stereo frames in " << el << " s ("
				  << total / el << " frames/s) -> " << dir.string() << "\n";
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"sim", {"render simulated stereo traversals under different lighting (-c sim.ini -o dir)", run});
}  // namespace cmd_sim
