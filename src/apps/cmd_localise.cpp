/* shadyloc localise: a live stereo run against a dual-channel keyframe map
 * with the combined system (docs/localisation.md). */
#include "Command.h"
#include "CommandLine.h"
#include "LocalisedFrame.h"
#include "LearnExperience.h"
#include "LocalisedView.h"

#include <shadyloc/core/ConfigLocation.h>
#include <shadyloc/core/Settings.h>
#include <shadyloc/datasets/LiveCapture.h>
#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/eval/LocaliseOutputs.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/localisation/LocaliseRun.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "shadyloc_commit.h"  // SHADYLOC_GIT_COMMIT, written at build time (cmake/WriteCommit.cmake)

namespace cmd_localise
{
using namespace shadyloc;
using namespace shadyloc::localisation;
using shadyloc::apps::learnExperience;
using shadyloc::apps::TLearnOptions;
namespace fs = std::filesystem;

std::vector<std::string> splitList(const std::string& s)
{
	std::vector<std::string> out;
	std::string w;
	for (const char c : s + ",")
		if (c == ',' || c == ' ')
		{
			if (!w.empty()) out.push_back(w);
			w.clear();
		}
		else
			w += c;
	return out;
}

std::string describeCamera(const geometry::TStereoCalib& c, int w, int h)
{
	return std::to_string(w) + "x" + std::to_string(h) + " px, " + c.asString();
}

bool sameCamera(const geometry::TStereoCalib& a, const geometry::TStereoCalib& b)
{
	const auto eq = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); };
	return eq(a.fx, b.fx) && eq(a.fy, b.fy) && eq(a.cx, b.cx) && eq(a.cy, b.cy) && eq(a.cxR, b.cxR) &&
		   eq(a.baseline, b.baseline);
}

/** The live run's camera (its first frame) must be the map's: landmarks
 * projected with another calibration find nothing, and the run would end
 * with no fix and exit 0 (eval refuses such pairs too). */
void checkLiveCamera(const CKeyframeMap& map, const std::string& mapPath, const std::string& liveWhat, const LocaliseRun& run)
{
	const auto& f = run.firstFrame();
	if (sameCamera(f.calib, map.calibration()) && f.size.width == map.imageWidth() && f.size.height == map.imageHeight())
		return;
	throw std::runtime_error(
		liveWhat + " (camera '" + f.camera + "': " + describeCamera(f.calib, f.size.width, f.size.height) +
		") is not of the camera of map '" + mapPath + "' (" +
		describeCamera(map.calibration(), map.imageWidth(), map.imageHeight()) +
		"): a map localises runs of the camera that surveyed it");
}

/** OUTDIR/view/frame_NNNNNN.png: the map and the live path so far. */
void writeView(const CKeyframeMap::Ptr& map, const std::vector<TLocalisationUpdate>& ups, const fs::path& dir)
{
	const auto& u = ups.back();
	render::SnapshotOptions o;
	o.width = 800;
	o.height = 600;
	o.title = "frame " + std::to_string(u.frame) + ": " + (u.localised() ? u.used + " fix" : std::string("no fix"));
	apps::renderLocalisedView(*map, ups, o, (dir / "view" / apps::viewFileName(u.frame)).string());
}

/** The options of --gif's pictures: --gif and its companions, --view-images
 * (--view N's pictures made as --gif's frames), --frame-width. */
struct TPictureArgs
{
	TCLAP::SwitchArg viewImages;
	TCLAP::ValueArg<std::string> gif;
	shadyloc::apps::NumberArg<int> gifEvery;
	shadyloc::apps::NumberArg<double> gifFps;
	shadyloc::apps::NumberArg<int> frameWidth;

	explicit TPictureArgs(shadyloc::apps::CommandLine& cli)
		: viewImages(
			  "", "view-images",
			  "with --view: the pictures are --gif's frames (each localiser's live image with its matches, above "
			  "the top-down view)",
			  cli.cmd()),
		  gif("", "gif",
			  "an animated GIF of the run: each localiser channel's live left image with its matches against the "
			  "map (green: inliers of its solve, red: the others) above the top-down view of the map and the live "
			  "path; written atomically, outside OUTDIR",
			  false, "", "OUT.gif", cli.cmd()),
		  gifEvery(cli, "", "gif-every", "with --gif: every N-th frame", 1, "N", 1, 1000000),
		  gifFps(cli, "", "gif-fps", "with --gif: frames shown per second", 8.0, "Hz", 1.0, 50.0),
		  frameWidth(cli, "", "frame-width", "width of --gif's frames and --view-images' pictures", 480, "px", 160, 1920)
	{
	}

	/** --gif's companions only with it, --view-images only with --view N,
	 * --frame-width only with either, a .gif name. */
	void check(bool view)
	{
		if (!gif.isSet() && (gifEvery.isSet() || gifFps.isSet()))
			throw std::runtime_error("--gif-every and --gif-fps go with --gif OUT.gif only");
		if (!view && viewImages.isSet()) throw std::runtime_error("--view-images goes with --view N only");
		if (frameWidth.isSet() && !gif.isSet() && !viewImages.isSet())
			throw std::runtime_error("--frame-width goes with --gif or --view-images only");
		std::string ext = fs::path(gif.getValue()).extension().string();
		std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
		if (gif.isSet() && ext != ".gif") throw std::runtime_error("--gif: '" + gif.getValue() + "' is not a .gif file name");
	}

	/** The recorder of the pictures asked for (null: none); the GIF goes to
	 * gifTmp, the stills to viewDir every viewEvery frames. */
	std::unique_ptr<apps::LocalisedFrameRecorder> recorder(
		LocalisationSystem& sys, const std::string& gifTmp, const fs::path& viewDir, int viewEvery)
	{
		if (!gif.isSet() && !viewImages.isSet()) return nullptr;
		return std::make_unique<apps::LocalisedFrameRecorder>(
			sys, apps::TFrameRecording{
					 gifTmp, gifEvery.getValue(), gifFps.getValue(), viewDir.string(),
					 viewImages.getValue() ? viewEvery : 0, frameWidth.getValue()});
	}
};

/** -i or --live, and --live's companions only with it. */
void checkLiveArguments(bool rawlog, bool live, bool camera, bool liveOnly)
{
	if (rawlog == live) throw std::runtime_error("give the live run as -i RAWLOG or as --live SOURCE (one of the two)");
	if (live && !camera) throw std::runtime_error("--live needs --camera CALIB.ini (the rectified stereo calibration)");
	if (!live && (camera || liveOnly))
		throw std::runtime_error("--camera, --live-right, --fps, --realtime and --queue go with --live only");
}

/** What an output must never replace for a live source: the file, or the
 * folder of an image sequence ("dir/%06d.png"), or nothing for a device. */
std::string liveInputPath(const std::string& source)
{
	if (datasets::isCameraDevice(source)) return std::string();
	if (source.find('%') != std::string::npos)
	{
		const fs::path dir = fs::path(source).parent_path();
		return dir.empty() ? "." : dir.string();
	}
	return source;
}

CKeyframeMap::Ptr loadMap(const std::string& mapPath)
{
	CKeyframeMap::Ptr map;
	try
	{
		map = CKeyframeMap::LoadFromFile(mapPath);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(std::string("map: ") + e.what());
	}
	if (map->isEmpty()) throw std::runtime_error("map '" + mapPath + "' has no keyframes: nothing to localise against");
	map->reportLoadProblems(std::cerr, mapPath);
	return map;
}

/** The capture's frames as the frame source's feed. */
filters::TObjectFeed feedOf(datasets::LiveCapture& capture)
{
	return {[c = &capture]() -> mrpt::serialization::CSerializable::Ptr { return c->next(); }, capture.name()};
}

/** summary.json's record of a live source: what was read and dropped. */
void recordLiveCapture(const datasets::LiveCapture& capture, eval::TLocaliseProvenance& prov)
{
	prov.liveHash = "not hashed (live source)";
	prov.live = true;
	prov.liveFramesRead = capture.grabbed();
	prov.liveFramesDropped = capture.dropped();
	prov.liveDropsWhenBehind = capture.dropsWhenBehind();
}

/** What the run localises against, with what, before it starts. */
void printHeader(const CKeyframeMap& map, const std::string& mapPath, const std::string& livePath, const LocaliseRun& lrun)
{
	std::cout << "map: " << mapPath << " (" << map.keyframeCount() << " keyframes, " << std::fixed << std::setprecision(1)
			  << map.pathLength() << " m)\nlive: " << livePath << " ('" << lrun.sensorLabel() << "')\n";
	for (size_t i = 0; i < lrun.source().channels().size(); i++)
		std::cout << "channel " << lrun.source().channels()[i].label << ": " << lrun.source().describeInput(i) << "\n";
	std::cout << "[localise]\n";
	lrun.system().options().dump(std::cout);
}

/** The run's result on stdout: coverage, truth, live counts, blind distance. */
void printResult(
	const std::vector<TLocalisationUpdate>& ups, const eval::TEvaluation& ev, bool withGt,
	const datasets::LiveCapture* capture, const std::string& outDir)
{
	std::cout << std::fixed << std::setprecision(1) << "frames " << ups.size() << ", in map " << ev.in_map_frames
			  << ", fixes " << ev.fixes << ": coverage " << 100 * ev.coverage_in_map << " % of in-map frames ("
			  << 100 * ev.coverage_all << " % of all)";
	for (const auto& s : ev.channels) std::cout << "; " << s.channel << " " << s.accepted << " (used " << s.used << ")";
	std::cout << "\n";
	if (withGt)
		std::cout << "ground truth: true coverage " << 100 * ev.true_coverage_in_map << " % (self-reported "
				  << 100 * ev.coverage_in_map << " %), false fixes " << ev.false_fixes << " (" << std::setprecision(2)
				  << 100 * ev.false_fix_share << " %)\n";
	if (capture)
		std::cout << "live: " << capture->grabbed() << " frames read from " << capture->name() << ", "
				  << capture->dropped() << " dropped (the localiser was behind)\n";
	std::cout << std::setprecision(1) << "blind: " << ev.blind_m << " m of " << ev.total_m << " m, first fix at frame "
			  << ev.first_fix_frame << "; -> " << outDir << "\n";
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Localises a live stereo run against a dual-channel keyframe map (shadyloc survey) with the combined "
		"system: live VO on the monochrome channel predicts for the localisers (mono, invariant), which run in "
		"parallel; the monochrome fix is used when it succeeds, else the invariant one, else VO dead-reckons. "
		"The run starts by a global search over the map (or at --start-kf). Writes OUTDIR/frames.csv, solves.csv, "
		"trajectory.tum, summary.json and timing.json (docs/localisation.md).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> mapArg("m", "map", "keyframe map (.kfmap)", true, "", "map.kfmap", cmd);
	TCLAP::ValueArg<std::string> in("i", "input", "live rawlog (colour stereo, or filtered by shadyloc filter: its channels are read); or --live", false, "", "live.rawlog", cmd);
	TCLAP::ValueArg<std::string> liveArg(
		"", "live",
		"frames as they arrive from what OpenCV's VideoCapture opens: a camera device number, a video file, or an "
		"image sequence such as 'dir/%06d.png'; side by side (left | right) unless --live-right; needs --camera",
		false, "", "SOURCE", cmd);
	TCLAP::ValueArg<std::string> liveRight("", "live-right", "with --live: the right camera's source", false, "", "SOURCE", cmd);
	TCLAP::ValueArg<std::string> cameraArg(
		"", "camera", "with --live: rectified calibration .ini ([left], [right], [stereo]; as `import folder`)", false, "",
		"calib.ini", cmd);
	shadyloc::apps::NumberArg<double> fpsArg(
		cli, "", "fps", "with --live: frame rate of a file or sequence (timestamps i / fps, and --realtime) [Hz]", 10.0,
		"Hz", 1e-3, 1000.0);
	TCLAP::SwitchArg realtime(
		"", "realtime", "with --live: play a file or sequence at --fps as a camera would, dropping frames when behind", cmd);
	shadyloc::apps::NumberArg<int> queueArg(
		cli, "", "queue", "with --live: frames read ahead at most (a camera drops the oldest beyond)", 2, "N", 1, 1000);
	TCLAP::ValueArg<std::string> out(
		"o", "output",
		"output directory (replaced as a whole if it is empty or an earlier localise output; any other folder is "
		"refused)",
		true, "", "OUTDIR", cmd);
	TCLAP::MultiArg<std::string> cfgArgs(
		"c", "config",
		"options .ini, may be repeated (sections of all files together): [localise], [localiser], "
		"[localiser.<channel>], [vo], [features], channel filter sections",
		false, "ini", cmd);
	TCLAP::ValueArg<std::string> gtArg(
		"", "gt", "live run's ground truth (TUM), in the world frame of the map's ground truth", false, "", "live.tum", cmd);
	TCLAP::ValueArg<std::string> locArg(
		"", "localisers", "localisers in policy order (default: [localise] localisers, else mono,invariant)", false, "",
		"mono,invariant", cmd);
	shadyloc::apps::NumberArg<int> threads(
		cli, "", "threads", "threads (default: [localise] threads, else 2)", 0, "N", 0, 64);
	shadyloc::apps::NumberArg<int> startKf(
		cli, "", "start-kf", "start at this map keyframe instead of by global search", -1, "id", -1, 1000000000);
	TCLAP::ValueArg<std::string> label("", "label", "sensor label of the live colour stereo camera (of a filtered rawlog: the camera its channels' labels start with)", false, "", "label", cmd);
	shadyloc::apps::NumberArg<int> viewArg(
		cli, "", "view",
		"every N frames, a top-down picture of the map and the live path so far (offscreen) in OUTDIR/view/", 0, "N", 0,
		1000000);
	TPictureArgs pictureArgs(cli);
	TCLAP::ValueArg<std::string> learnArg(
		"", "learn",
		"where the run goes blind for more than --learn-blind-m, add its keyframes there to a copy of the map as a "
		"new experience, written to this file (never over the map)",
		false, "", "OUT.kfmap", cmd);
	shadyloc::apps::NumberArg<double> learnBlind(
		cli, "", "learn-blind-m", "with --learn: blind stretches longer than this are learnt [m]", 10.0, "m", 0.0, 1e6);
	shadyloc::apps::NumberArg<double> learnMargin(
		cli, "", "learn-margin-m", "with --learn: ... with this much of the run on either side, to link them [m]", 5.0,
		"m", 0.0, 1e6);
	TCLAP::SwitchArg quiet("q", "quiet", "no progress output", cmd);
	TCLAP::SwitchArg debug(
		"", "debug",
		"per frame and localiser on stderr: keyframe, predicted offset from it, matches, inliers, gate, status", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	const bool talk = !quiet.getValue();

	// ---- inputs, checked before any work
	const std::string mapPath = mapArg.getValue(), livePath = in.isSet() ? in.getValue() : liveArg.getValue();
	const bool live = liveArg.isSet();
	checkLiveArguments(in.isSet(), live, cameraArg.isSet(), liveRight.isSet() || fpsArg.isSet() || realtime.isSet() || queueArg.isSet());
	pictureArgs.check(viewArg.getValue() > 0);
	if (learnArg.isSet() && live) throw std::runtime_error("--learn: only with a live rawlog (-i), which it surveys");
	if ((learnBlind.isSet() || learnMargin.isSet()) && !learnArg.isSet())
		throw std::runtime_error("--learn-blind-m, --learn-margin-m: only with --learn");
	if (learnArg.isSet() && fs::path(learnArg.getValue()).extension() != CKeyframeMap::kFileExtension)
		throw std::runtime_error("--learn '" + learnArg.getValue() + "': map files end in " + CKeyframeMap::kFileExtension);
	if (!fs::exists(mapPath)) throw std::runtime_error("map '" + mapPath + "' does not exist");
	if (!live && !fs::exists(livePath)) throw std::runtime_error("live rawlog '" + livePath + "' does not exist");
	std::string cfgText, cfgWhat;
	cfgText = core::layeredConfigText(cfgArgs.getValue());
	for (const auto& c : cfgArgs.getValue()) cfgWhat += (cfgWhat.empty() ? "" : " + ") + c;
	if (cfgWhat.empty()) cfgWhat = "(no config)";
	mrpt::config::CConfigFileMemory cfg(cfgText);
	std::optional<io::Trajectory> gt;
	if (gtArg.isSet()) gt = io::readTum(gtArg.getValue());
	// Every options struct the run reads, before any work; an error names
	// the file and line of the setting at fault, as eval's do.
	try
	{
		checkLocaliseConfig(cfg, locArg.isSet() ? splitList(locArg.getValue()) : std::vector<std::string>{}, cfgWhat);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(core::configError(cfgArgs.getValue(), cfgWhat, e.what()));
	}

	// The output folder is checked before the run: it may hold no input and
	// replaces only an earlier localise output.
	io::OutputTransaction outputs;
	outputs.addInput(mapPath, "map");
	if (live)
	{
		for (const auto& src : {liveArg.getValue(), liveRight.getValue()})
			if (const std::string p = src.empty() ? "" : liveInputPath(src); !p.empty()) outputs.addInput(p, "live source");
		outputs.addInput(cameraArg.getValue(), "camera calibration");
	}
	else
	{
		outputs.addInput(livePath, "live rawlog");
		outputs.addInput(io::imagesDirFor(livePath), "live rawlog's images folder");
	}
	if (gtArg.isSet()) outputs.addInput(gtArg.getValue(), "ground truth");
	for (const auto& c : cfgArgs.getValue()) outputs.addInput(c, "config");
	const fs::path dir = outputs.addDirectory(out.getValue(), "output folder", "shadyloc localise output");
	const std::string gifTmp = pictureArgs.gif.isSet() ? outputs.addFile(pictureArgs.gif.getValue(), "--gif") : "";
	const std::string learnTmp = learnArg.isSet() ? outputs.addFile(learnArg.getValue(), "--learn map") : "";

	const CKeyframeMap::Ptr map = loadMap(mapPath);

	TLocaliseRunOptions ro;
	if (locArg.isSet())
	{
		ro.localisers = splitList(locArg.getValue());
		if (ro.localisers.empty()) throw std::runtime_error("--localisers: names no localiser (mono, invariant)");
	}
	ro.threads = threads.getValue();
	ro.sensorLabel = label.getValue();
	ro.configWhat = cfgWhat;
	if (startKf.isSet() && startKf.getValue() < 0)
		throw std::runtime_error(
			"--start-kf " + std::to_string(startKf.getValue()) + ": the map has keyframes 0.." +
			std::to_string(map->keyframeCount() - 1));
	ro.startKf = startKf.isSet() ? startKf.getValue() : -1;
	std::unique_ptr<datasets::LiveCapture> capture;
	std::unique_ptr<LocaliseRun> run;
	if (live)
	{
		datasets::TLiveCaptureOptions lo;
		lo.source = liveArg.getValue();
		lo.rightSource = liveRight.getValue();
		lo.calibIni = cameraArg.getValue();
		lo.fps = fpsArg.getValue();
		lo.realtime = realtime.getValue();
		lo.queue = static_cast<size_t>(queueArg.getValue());
		capture = std::make_unique<datasets::LiveCapture>(lo);
		run = std::make_unique<LocaliseRun>(cfg, map, mapPath, feedOf(*capture), ro);
	}
	else
		run = std::make_unique<LocaliseRun>(cfg, map, mapPath, livePath, ro);
	LocaliseRun& lrun = *run;
	checkLiveCamera(*map, mapPath, live ? "live source " + capture->name() : "live rawlog '" + livePath + "'", lrun);
	auto& sys = lrun.system();
	if (debug.getValue()) sys.setMinLoggingLevel(mrpt::system::LVL_DEBUG);
	if (talk) printHeader(*map, mapPath, livePath, lrun);
	size_t droppedShown = 0;
	const int viewEvery = viewArg.getValue();
	if (viewEvery > 0) fs::create_directories(dir / "view");
	const auto pictures = pictureArgs.recorder(sys, gifTmp, dir / "view", viewEvery);
	const auto& ups = lrun.run([&](const TLocalisationUpdate& u) {
		if (pictures) pictures->onFrame(*map, lrun.updates());
		if (viewEvery > 0 && !pictureArgs.viewImages.getValue() && u.frame % size_t(viewEvery) == 0)
			writeView(map, lrun.updates(), dir);
		if (!talk || u.frame % 50 != 0) return;
		std::cout << "frame " << u.frame << ": " << (u.localised() ? u.used : std::string("none"));
		if (capture && capture->dropped() > droppedShown)
		{
			droppedShown = capture->dropped();
			std::cout << " (behind the camera: " << droppedShown << " frames dropped so far)";
		}
		std::cout << std::endl;
	});

	// ---- evaluation
	const eval::TEvaluation ev = eval::evaluate(ups, *map, gt ? &*gt : nullptr);

	// ---- outputs, all or nothing
	eval::TLocaliseProvenance prov;
	prov.buildCommit = SHADYLOC_GIT_COMMIT;
	prov.configWhat = cfgWhat;
	prov.configText = cfgText;
	prov.mapPath = mapPath;
	prov.livePath = livePath;
	if (gt) prov.gtPath = gtArg.getValue();
	prov.startKf = startKf.getValue();
	if (capture) recordLiveCapture(*capture, prov);
	eval::writeLocaliseOutputs(dir.string(), ups, ev, *map, sys.options(), prov);
	if (pictures) pictures->finish();
	if (learnArg.isSet())
	{
		TLearnOptions lo;
		lo.blind_m = learnBlind.getValue();
		lo.margin_m = learnMargin.getValue();
		const auto learnt = learnExperience(cfg, cfgWhat, *map, livePath, gt, label.getValue(), ups, lo, std::cout);
		(learnt ? *learnt : *map).saveToFile(learnTmp);
	}
	outputs.commit();

	printResult(ups, ev, gt.has_value(), capture.get(), out.getValue());
	if (pictureArgs.gif.isSet())
		std::cout << "gif: " << pictures->gifFrames() << " frames -> " << pictureArgs.gif.getValue() << "\n";
	return 0;
}

shadyloc::apps::RegisterCommand reg(
	"localise",
	{"a live run against a keyframe map, combined system (-m MAP -i live.rawlog -o OUTDIR [-c ini] [--gt live.tum] "
	 "[--localisers mono,invariant] [--view N [--view-images]] [--gif OUT.gif [--gif-every N] [--gif-fps F]] "
	 "[--learn OUT.kfmap])",
	 run});
}  // namespace cmd_localise
