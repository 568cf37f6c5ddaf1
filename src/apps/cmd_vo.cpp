/* shadyloc vo: stereo visual odometry over a rawlog, on one image channel. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/vo/Channel.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

namespace
{
using namespace shadyloc;

bool endsWith(const std::string& s, const std::string& suf)
{
	return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}
bool isDerivedLabel(const std::string& l)
{
	return endsWith(l, "_mono") || endsWith(l, "_inv") || endsWith(l, "_lin");
}

/** The invariant parameters `shadyloc filter` recorded at the head of a
 * filtered rawlog, if it holds such a record with an invariant filter. */
std::optional<image::InvariantParams> recordedInvariantParams(const std::string& path)
{
	const std::string rec = filters::readPipelineRecord(path);
	if (rec.empty()) return std::nullopt;
	mrpt::config::CConfigFileMemory cfg(rec);
	const auto pipeline = filters::FilterPipeline::FromConfig(cfg, path + " (filter record)");
	for (const auto& f : pipeline.filters)
		if (const auto inv = std::dynamic_pointer_cast<CFilterInvariant>(f)) return inv->params();
	return std::nullopt;
}

/** Label of an already-filtered stereo stream for this channel in the first
 * objects of the rawlog, or "" if there is none (then colour is converted). */
std::string findFilteredLabel(const std::string& path, const std::string& suffix, const std::string& base)
{
	io::RawlogReader rd(path);
	for (int i = 0; i < 200; i++)
	{
		const auto obj = rd.next();
		if (!obj) break;
		for (const auto& o : io::observationsIn(obj))
			if (IS_CLASS(*o, mrpt::obs::CObservationStereoImages) && endsWith(o->sensorLabel, suffix) &&
				(base.empty() || o->sensorLabel == base + suffix))
				return o->sensorLabel;
	}
	return "";
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Keyframe-based stereo visual odometry on one image channel. Reads a rawlog of "
		"CObservationStereoImages (rectified); uses the <label>_mono / <label>_inv observations "
		"of a filtered rawlog when present, otherwise converts the colour images on the fly. "
		"Writes the left camera's poses in the first frame (TUM).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> in("i", "input", "input rawlog", true, "", "run.rawlog", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "trajectory (TUM)", true, "", "traj.tum", cmd);
	TCLAP::ValueArg<std::string> channel(
		"", "channel", "mono | invariant (default: [vo] channel of the config, else mono)", false, "",
		"mono|invariant", cmd);
	TCLAP::ValueArg<std::string> cfgArg(
		"c", "config", "options .ini ([vo], [features], [invariant]; see config/vo.ini)", false, "",
		"vo.ini", cmd);
	TCLAP::ValueArg<std::string> stats("", "stats", "per-frame CSV", false, "", "stats.csv", cmd);
	TCLAP::ValueArg<std::string> kfOut(
		"", "keyframes", "keyframe chain CSV (id, frame, timestamp, T_prevkf_kf, covariance diagonal)",
		false, "", "keyframes.csv", cmd);
	TCLAP::ValueArg<std::string> label(
		"", "label", "sensor label of the stereo camera (default: the first one found)", false, "",
		"label", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no option dump or progress", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	// Outputs first: refused before any work if one of them is an input or
	// cannot be written; committed together at the end.
	io::OutputTransaction outputs;
	outputs.addInput(in.getValue(), "input rawlog");
	if (std::filesystem::is_directory(io::imagesDirFor(in.getValue())))
		outputs.addInput(io::imagesDirFor(in.getValue()), "images folder of the input");
	if (cfgArg.isSet()) outputs.addInput(cfgArg.getValue(), "config");
	const std::string trajTmp = outputs.addFile(out.getValue(), "trajectory (-o)");
	const std::string statsTmp = stats.isSet() ? outputs.addFile(stats.getValue(), "--stats") : "";
	const std::string kfTmp = kfOut.isSet() ? outputs.addFile(kfOut.getValue(), "--keyframes") : "";

	std::unique_ptr<mrpt::config::CConfigFileBase> cfg;
	if (cfgArg.isSet())
	{
		if (!std::filesystem::exists(cfgArg.getValue()))
			throw std::runtime_error("config file '" + cfgArg.getValue() + "' does not exist");
		cfg = std::make_unique<mrpt::config::CConfigFile>(cfgArg.getValue());
	}
	else
		cfg = std::make_unique<mrpt::config::CConfigFileMemory>("");
	if (!std::filesystem::exists(in.getValue()))
		throw std::runtime_error("input rawlog '" + in.getValue() + "' does not exist");

	const auto conv = vo::ChannelConverter::FromConfig(*cfg, channel.getValue());
	// [vo] / [features], then the channel's overrides ([vo.mono], [features.invariant]).
	const vo::TStereoVOOptions vopt = vo::voOptionsFor(*cfg, conv.channel());
	const features::TStereoFeatureOptions fopt = vo::featureOptionsFor(*cfg, conv.channel());
	vo::StereoVO vo(vopt, fopt);
	vo.setMinLoggingLevel(quiet.getValue() ? mrpt::system::LVL_ERROR : mrpt::system::LVL_WARN);

	const std::string suffix = vo::channelSuffix(conv.channel());
	const std::string filtered = findFilteredLabel(in.getValue(), suffix, label.getValue());
	if (!quiet.getValue())
	{
		std::cout << "channel: " << conv.asString() << "\n"
				  << (filtered.empty() ? "input: colour stereo, converted on the fly\n"
									   : "input: filtered observations '" + filtered + "'\n")
				  << "[vo]\n";
		vopt.dumpToTextStream(std::cout);
		std::cout << "[features]\n";
		fopt.dumpToTextStream(std::cout);
	}
	if (!filtered.empty() && conv.channel() == vo::Channel::Invariant)
	{
		// The images are used as they are; say which transform made them, and
		// warn when the config describes another one (a map and a live run
		// must use the same, or their invariant images are not comparable).
		const auto rec = recordedInvariantParams(in.getValue());
		if (!rec)
			std::cerr << "warning: " << in.getValue()
					  << ": no filter record; the parameters of its invariant images are unknown\n";
		else if (!rec->sameImageAs(conv.invariantParams()))
			std::cerr << "warning: " << in.getValue() << ": its invariant images were made with "
					  << rec->asString() << " (filter record), not with the config's [invariant] "
					  << conv.invariantParams().asString() << "; the recorded images are used\n";
		else if (!quiet.getValue())
			std::cout << "invariant images made with the config's parameters (filter record)\n";
	}

	io::RawlogReader rd(in.getValue());
	std::string useLabel = filtered.empty() ? label.getValue() : filtered;
	eval::Trajectory traj;
	std::ostringstream csv;
	csv << "frame,timestamp,features,stereo_matches,tracked,inliers,keyframe,status,rms_px,"
		   "ms_detect,ms_stereo,ms_describe,ms_match,ms_ransac,ms_solve,ms_total\n";
	csv << std::fixed;
	geometry::TStereoCalib calib;
	cv::Size size;
	size_t nTracked = 0;
	double msSum = 0;
	while (const auto obj = rd.next())
	{
		for (const auto& o : io::observationsIn(obj))
		{
			auto st = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(o);
			if (!st) continue;
			if (useLabel.empty())
			{
				if (isDerivedLabel(st->sensorLabel)) continue;
				useLabel = st->sensorLabel;
			}
			if (st->sensorLabel != useLabel) continue;
			if (!st->hasImageRight)
				throw std::runtime_error(
					rd.where("stereo observation '" + st->sensorLabel + "'") + ": has no right image");
			io::loadExternalImages(*st);
			const cv::Mat& L = st->imageLeft.asCvMatRef();
			const cv::Mat& R = st->imageRight.asCvMatRef();
			const std::string where = rd.where("stereo observation '" + st->sensorLabel + "'");
			if (L.empty() || R.empty() || L.size() != R.size() || L.type() != R.type())
				throw std::runtime_error(
					where + ": empty left/right images, or of different sizes or types (grey/colour)" +
					io::externalImagesOf(*st));
			if (traj.empty())
			{
				calib = geometry::TStereoCalib::FromObservation(*st);
				size = L.size();
				if (!quiet.getValue()) std::cout << "calibration: " << calib.asString() << "\n";
			}
			else if (L.size() != size)
				throw std::runtime_error(where + ": image size changed within the run");
			cv::Mat l8, r8;
			if (L.type() == CV_8UC1 && (!filtered.empty() || conv.channel() == vo::Channel::Mono))
			{
				l8 = L;
				r8 = R;
			}
			else
			{
				try
				{
					conv.convert(L, l8);
					conv.convert(R, r8);
				}
				catch (const std::exception& e)
				{
					throw std::runtime_error(where + ": " + e.what());
				}
			}
			const double t = mrpt::Clock::toDouble(st->timestamp);
			const auto res = vo.process(l8, r8, calib, t);
			traj.push_back({t, res.T_world_curr});
			nTracked += vo::isTracked(res.status);
			msSum += res.ms.total;
			csv << res.frame << ',' << std::setprecision(6) << res.timestamp << ',' << res.features << ','
				<< res.stereo << ',' << res.tracked << ',' << res.inliers << ',' << int(res.keyframe) << ','
				<< vo::toString(res.status) << ',' << std::setprecision(3) << res.rms_px << ','
				<< res.ms.detect << ',' << res.ms.stereo << ',' << res.ms.describe << ',' << res.ms.match
				<< ',' << res.ms.ransac << ',' << res.ms.solve << ',' << res.ms.total << '\n';
			if (!quiet.getValue() && res.frame % 100 == 0)
				std::cout << "frame " << res.frame << " (" << std::setprecision(0) << 100 * rd.progress()
						  << "%)\n";
		}
	}
	if (traj.empty())
		throw std::runtime_error(
			in.getValue() + ": no stereo observations" +
			(useLabel.empty() ? std::string() : " labelled '" + useLabel + "'"));
	eval::writeTum(trajTmp, traj);
	if (stats.isSet())
	{
		std::ofstream f(statsTmp);
		f << csv.str();
		f.close();
		if (!f) throw std::runtime_error("--stats '" + stats.getValue() + "': write failed (disk full?)");
	}
	if (kfOut.isSet())
	{
		std::ofstream f(kfTmp);
		f << "id,frame,timestamp,tx,ty,tz,qx,qy,qz,qw,chain_break,landmarks,"
			 "var_x,var_y,var_z,var_rx,var_ry,var_rz\n"
		  << std::setprecision(9);
		for (const auto& k : vo.keyframes())
		{
			const Eigen::Quaterniond q(k.T_prevkf_kf.linear());
			const auto& p = k.T_prevkf_kf.translation();
			f << k.id << ',' << k.frame << ',' << k.timestamp << ',' << p.x() << ',' << p.y() << ','
			  << p.z() << ',' << q.x() << ',' << q.y() << ',' << q.z() << ',' << q.w() << ','
			  << int(k.chain_break) << ',' << k.meas.size();
			for (int i = 0; i < 6; i++) f << ',' << k.cov(i, i);
			f << '\n';
		}
		f.close();
		if (!f) throw std::runtime_error("--keyframes '" + kfOut.getValue() + "': write failed (disk full?)");
	}
	outputs.commit();
	std::cout << std::setprecision(2) << std::fixed << "frames: " << traj.size() << ", tracked: " << nTracked
			  << ", keyframes: " << vo.keyframes().size() << ", mean " << msSum / traj.size()
			  << " ms/frame; trajectory -> " << out.getValue() << "\n";
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"vo", {"stereo VO on one channel (-i run.rawlog --channel mono|invariant -o traj.tum [-c ini] [--stats csv])",
			  run});
}  // namespace
