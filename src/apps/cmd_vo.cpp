/* shadyloc vo: stereo visual odometry over a rawlog, on one image channel. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/filters/Channel.h>
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/io/Csv.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/vo/ChannelOptions.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/vo/StereoVO.h>
#include <shadyloc/vo/VOConfig.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <filesystem>
#include <iomanip>
#include <iostream>

namespace cmd_vo
{
using namespace shadyloc;

/** The images of a filtered rawlog are used as they are; says which filter
 * made them, and warns when the config describes another one (a map and a
 * live run must use the same, or their channel images are not comparable). */
void warnAboutRecord(const filters::TChannelInput& input, const filters::TChannel& ch, const std::string& rawlog, bool quiet)
{
	if (!input.recorded)
		std::cerr << "warning: " << rawlog << ": no filter record"
				  << (input.hasRecord ? " of suffix " + ch.suffix() : std::string()) << "; the parameters of its "
				  << ch.label << " images are unknown\n";
	else if (!input.recorded->sameImagesAs(*ch.filter))
		std::cerr << "warning: " << rawlog << ": its " << ch.label << " images were made with "
				  << input.recorded->describe() << " (filter record), not with the config's [" << ch.label << "] "
				  << ch.filter->describe() << "; the recorded images are used\n";
	else if (!quiet)
		std::cout << ch.label << " images made with the config's parameters (filter record)\n";
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

	const auto cfg = vo::loadVOConfig(cfgArg.isSet() ? cfgArg.getValue() : "");
	if (!std::filesystem::exists(in.getValue()))
		throw std::runtime_error("input rawlog '" + in.getValue() + "' does not exist");

	// The channel is the filter that makes its images: a section of the
	// config (class = CFilterInvariant, ...) or a built-in one.
	const std::string cfgName = cfgArg.isSet() ? cfgArg.getValue() : std::string("(no config)");
	if (cfg->keyExists("vo", "channel_order"))
		throw std::invalid_argument(
			"'" + cfgName + "': [vo] channel_order: moved to the channel's filter section "
			"([mono] class = CFilterMonochrome, channel_order = ...)");
	const filters::TChannel ch = filters::channelFromConfig(
		*cfg, channel.isSet() ? channel.getValue() : cfg->read_string("vo", "channel", "mono"), cfgName);
	// [vo] / [features], then the channel's overrides ([vo.mono], [features.invariant]).
	const vo::TStereoVOOptions vopt = vo::voOptionsFor(*cfg, ch.label);
	const features::TStereoFeatureOptions fopt = vo::featureOptionsFor(*cfg, ch.label);
	vo::StereoVO vo(vopt, fopt);
	vo.setMinLoggingLevel(quiet.getValue() ? mrpt::system::LVL_ERROR : mrpt::system::LVL_WARN);

	filters::TChannelFrameSourceOptions so;
	so.camera = label.getValue();
	filters::ChannelFrameSource source(in.getValue(), {ch}, so);
	const filters::TChannelInput& input = source.input(0);
	if (!quiet.getValue())
	{
		std::cout << "channel: " << ch.asString() << "\n"
				  << (input.filtered ? "input: filtered observations '" + input.sensorLabel + "'\n"
									 : "input: colour stereo, converted on the fly\n")
				  << "[vo]\n";
		vopt.dumpToTextStream(std::cout);
		std::cout << "[features]\n";
		fopt.dumpToTextStream(std::cout);
	}
	if (input.filtered) warnAboutRecord(input, ch, in.getValue(), quiet.getValue());

	io::Trajectory traj;
	std::unique_ptr<io::CsvWriter> csv;
	if (stats.isSet())
	{
		csv = std::make_unique<io::CsvWriter>(
			statsTmp,
			"frame,timestamp,features,stereo_matches,tracked,inliers,keyframe,status,rms_px,"
			"ms_detect,ms_stereo,ms_describe,ms_match,ms_ransac,ms_solve,ms_total");
		csv->out() << std::fixed;
	}
	size_t nTracked = 0;
	double msSum = 0;
	filters::TChannelFrame fr;
	while (source.next(fr))
	{
		if (fr.index == 0 && !quiet.getValue()) std::cout << "calibration: " << fr.calib.asString() << "\n";
		const auto& img = fr.channels[0];
		if (img.left.type() != CV_8UC1)
			throw std::runtime_error(
				fr.where + "channel '" + ch.label + "' gives " + std::to_string(img.left.channels()) +
				"-channel images; the VO needs a grey channel");
		const auto res = vo.process(img.left, img.right, fr.calib, fr.timestamp);
		traj.push_back({fr.timestamp, res.T_world_curr});
		nTracked += vo::isTracked(res.status);
		msSum += res.ms.total;
		if (csv)
			csv->out() << res.frame << ',' << std::setprecision(6) << res.timestamp << ',' << res.features << ','
					   << res.stereo << ',' << res.tracked << ',' << res.inliers << ',' << int(res.keyframe) << ','
					   << vo::toString(res.status) << ',' << std::setprecision(3) << res.rms_px << ','
					   << res.ms.detect << ',' << res.ms.stereo << ',' << res.ms.describe << ',' << res.ms.match
					   << ',' << res.ms.ransac << ',' << res.ms.solve << ',' << res.ms.total << '\n';
		if (!quiet.getValue() && res.frame % 100 == 0)
			std::cout << "frame " << res.frame << " (" << std::setprecision(0) << 100 * source.progress()
					  << "%)\n";
	}
	if (traj.empty()) throw std::runtime_error(source.noFramesMessage());
	io::writeTum(trajTmp, traj);
	if (csv) csv->commit();
	if (kfOut.isSet())
	{
		io::CsvWriter f(
			kfTmp,
			"id,frame,timestamp,tx,ty,tz,qx,qy,qz,qw,chain_break,landmarks,"
			"var_x,var_y,var_z,var_rx,var_ry,var_rz");
		f.out() << std::setprecision(9);
		for (const auto& k : vo.keyframes())
		{
			const Eigen::Quaterniond q(k.T_prevkf_kf.linear());
			const auto& p = k.T_prevkf_kf.translation();
			f.out() << k.id << ',' << k.frame << ',' << k.timestamp << ',' << p.x() << ',' << p.y() << ','
					<< p.z() << ',' << q.x() << ',' << q.y() << ',' << q.z() << ',' << q.w() << ','
					<< int(k.chain_break) << ',' << k.meas.size();
			for (int i = 0; i < 6; i++) f.out() << ',' << k.cov(i, i);
			f.out() << '\n';
		}
		f.commit();
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
}  // namespace cmd_vo
