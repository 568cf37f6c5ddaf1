/* shadyloc import <kitti|middlebury|folder|robotcar>: datasets -> stereo rawlog. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/datasets/Folder.h>
#include <shadyloc/datasets/Kitti.h>
#include <shadyloc/datasets/Middlebury.h>
#include <shadyloc/datasets/RobotCar.h>


#include <cstring>
#include <optional>
#include <sstream>
#include <vector>
#include <iostream>
#include <memory>

namespace cmd_import
{
using namespace shadyloc::datasets;

/** The options every importer takes. */
struct CommonArgs
{
	explicit CommonArgs(shadyloc::apps::CommandLine& cli)
		: maxFrames(cli, "", "max-frames", "import at most N frames (0: all)", 0, "N"),
		  every(cli, "", "progress-every", "report progress every N frames (0: never)", 100, "N")
	{
		for (TCLAP::Arg* a : std::initializer_list<TCLAP::Arg*>{&out, &label, &ext, &quiet}) cli.cmd().add(a);
	}
	TCLAP::ValueArg<std::string> out{"o", "output", "output rawlog", true, "", "out.rawlog"};
	TCLAP::ValueArg<std::string> label{
		"", "sensor-label", "sensor label of the stereo observations", false, "CAMERA", "label"};
	TCLAP::SwitchArg ext{
		"", "external-images", "store images as PNG files in <out>_Images/ (not inside the rawlog)"};
	shadyloc::apps::NumberArg<size_t> maxFrames;
	shadyloc::apps::NumberArg<size_t> every;
	TCLAP::SwitchArg quiet{"q", "quiet", "no progress output"};

	TImportOptions options()
	{
		TImportOptions o;
		o.sensorLabel = label.getValue();
		o.externalImages = ext.getValue();
		o.maxFrames = maxFrames.getValue();
		o.progressEvery = every.getValue();
		return o;
	}
	void setup(mrpt::system::COutputLogger& log)
	{
		log.setMinLoggingLevel(quiet.getValue() ? mrpt::system::LVL_WARN : mrpt::system::LVL_INFO);
	}
};

void report(const TImportResult& r)
{
	std::cout << "Imported " << r.frames << " stereo frame(s) into '" << r.rawlogPath << "'\n"
			  << "  left : " << r.leftCamera.ncols << "x" << r.leftCamera.nrows
			  << " fx=" << r.leftCamera.fx() << " fy=" << r.leftCamera.fy()
			  << " cx=" << r.leftCamera.cx() << " cy=" << r.leftCamera.cy() << "\n"
			  << "  right: fx=" << r.rightCamera.fx() << " fy=" << r.rightCamera.fy()
			  << " cx=" << r.rightCamera.cx() << " cy=" << r.rightCamera.cy()
			  << "  baseline " << r.rightCameraPose.x() << " m\n";
	if (!r.groundTruthPath.empty()) std::cout << "  ground truth: '" << r.groundTruthPath << "'\n";
}

int runKitti(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Imports a KITTI odometry sequence (colour cameras image_2 / image_3, calib.txt P2/P3, "
		"times.txt, poses/NN.txt if present -> <out>_gt.tum) into a rawlog of "
		"CObservationStereoImages.");
	auto& cmd = cli.cmd();
	TCLAP::UnlabeledValueArg<std::string> root("root", "KITTI root (holds sequences/ and poses/)", true, "", "ROOT", cmd);
	TCLAP::ValueArg<std::string> seq("s", "sequence", "sequence number, e.g. 00", false, "00", "NN", cmd);
	CommonArgs common(cli);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	KittiImporter imp;
	imp.options = common.options();
	common.setup(imp);
	report(imp.run(root.getValue(), seq.getValue(), common.out.getValue()));
	return 0;
}

int runMiddlebury(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Imports a Middlebury 2014 stereo scene (im0.png, im1.png, calib.txt) as a rawlog with "
		"one stereo frame; both principal points and the baseline kept exactly.");
	auto& cmd = cli.cmd();
	TCLAP::UnlabeledValueArg<std::string> scene("scene", "scene directory", true, "", "SCENE_DIR", cmd);
	TCLAP::ValueArg<std::string> left("", "left-image", "left image file in the scene", false, "im0.png", "name", cmd);
	TCLAP::ValueArg<std::string> right(
		"", "right-image", "right image file (im1E.png, im1L.png: lighting variants)", false, "im1.png", "name", cmd);
	shadyloc::apps::NumberArg<double> stamp(cli, "", "timestamp", "frame timestamp [s since Unix epoch] (>= 0)", 0.0, "s", 0.0);
	CommonArgs common(cli);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	MiddleburyImporter imp;
	imp.options = common.options();
	imp.leftImage = left.getValue();
	imp.rightImage = right.getValue();
	imp.timestamp = stamp.getValue();
	common.setup(imp);
	report(imp.run(scene.getValue(), common.out.getValue()));
	return 0;
}

int runFolder(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Imports a folder of left images and a folder of right images (paired by sorted file "
		"name) with a calibration .ini (see config/folder_calib_example.ini).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> left("", "left", "left image directory", true, "", "DIR", cmd);
	TCLAP::ValueArg<std::string> right("", "right", "right image directory", true, "", "DIR", cmd);
	TCLAP::ValueArg<std::string> calib("", "calib", "calibration .ini", true, "", "calib.ini", cmd);
	shadyloc::apps::NumberArg<double> rate(cli, "", "rate", "frame rate [Hz] (> 0; timestamps start + i/rate)", 0, "HZ", 1e-9);
	TCLAP::ValueArg<std::string> times("", "times", "timestamps file, one [s] per pair", false, "", "times.txt", cmd);
	shadyloc::apps::NumberArg<double> start(cli, "", "start-time", "timestamp of frame 0 with --rate [s] (>= 0)", 0, "s", 0.0);
	CommonArgs common(cli);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	if (rate.isSet() == times.isSet()) return cli.usageError("give exactly one of --rate HZ or --times FILE");
	if (start.isSet() && !rate.isSet()) return cli.usageError("--start-time goes with --rate (--times gives every timestamp)");
	FolderImporter imp;
	imp.options = common.options();
	imp.rateHz = rate.getValue();
	imp.timesFile = times.getValue();
	imp.startTime = start.getValue();
	common.setup(imp);
	report(imp.run(left.getValue(), right.getValue(), calib.getValue(), common.out.getValue()));
	return 0;
}

/** n comma-separated numbers; nullopt with `why` (naming `flag`) if malformed. */
std::optional<std::vector<double>> parseNumbers(const std::string& text, size_t n, const std::string& flag, std::string& why)
{
	std::vector<double> v;
	std::string tok;
	std::istringstream ss(text);
	try
	{
		while (std::getline(ss, tok, ',')) v.push_back(shadyloc::apps::parseNumber<double>(tok));
	}
	catch (const std::invalid_argument& e)
	{
		why = flag + ": " + e.what();
		return std::nullopt;
	}
	if (v.size() != n)
	{
		why = flag + ": '" + text + "' is not " + std::to_string(n) + " comma-separated numbers";
		return std::nullopt;
	}
	return v;
}

/** "X,Y,W,H" [px] -> rect; nullopt with `why` set if malformed. */
std::optional<cv::Rect> parseCrop(const std::string& text, std::string& why)
{
	std::vector<int> v;
	std::string tok;
	std::istringstream ss(text);
	try
	{
		while (std::getline(ss, tok, ','))
			v.push_back(shadyloc::apps::parseNumber<int>(tok));
	}
	catch (const std::invalid_argument& e)
	{
		why = std::string("--crop: ") + e.what();
		return std::nullopt;
	}
	if (v.size() != 4 || v[0] < 0 || v[1] < 0 || v[2] < 1 || v[3] < 1)
	{
		why = "--crop: '" + text + "' is not X,Y,W,H (pixels, X and Y >= 0, W and H >= 1)";
		return std::nullopt;
	}
	return cv::Rect(v[0], v[1], v[2], v[3]);
}

int runRobotCar(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Imports the wide stereo pair of an Oxford RobotCar traversal (stereo.timestamps, stereo/left and "
		"stereo/right raw Bayer GBRG PNGs, gps/ins.csv) with the RobotCar SDK's camera models "
		"(stereo_wide_left/right .txt and _distortion_lut.bin): images demosaiced (bilinear unless --demosaic) and remapped "
		"through the SDK's look-up tables (undistorted and rectified), calibration from the models; ground "
		"truth of the left camera from the INS, interpolated to image times, with the SDK's extrinsics "
		"(stereo.txt, ins.txt) -> <out>_gt.tum (docs/datasets.md).");
	auto& cmd = cli.cmd();
	TCLAP::UnlabeledValueArg<std::string> root("traversal", "RobotCar traversal folder (holds stereo/, stereo.timestamps, gps/)", true, "", "TRAVERSAL", cmd);
	TCLAP::ValueArg<std::string> models("m", "models", "the SDK's camera models folder", true, "", "MODELS_DIR", cmd);
	TCLAP::ValueArg<std::string> extr("e", "extrinsics", "the SDK's extrinsics folder (stereo.txt, ins.txt); needed for ground truth", false, "", "EXTRINSICS_DIR", cmd);
	TCLAP::SwitchArg noGt("", "no-ground-truth", "do not read gps/ins.csv (no <out>_gt.tum)", cmd);
	TCLAP::ValueArg<std::string> origin(
		"", "gt-origin", "subtract this UTM point from the ground truth [m] (the same for every traversal of a route)",
		false, "", "NORTHING,EASTING,DOWN", cmd);
	shadyloc::apps::NumberArg<size_t> first(cli, "", "first-frame", "first frame imported (0-based line of stereo.timestamps)", 0, "N");
	shadyloc::apps::NumberArg<size_t> stride(cli, "", "stride", "import every K-th frame from --first-frame (>= 1)", 1, "K", 1);
	std::vector<std::string> methods{"bilinear", "edge-aware", "half"};
	TCLAP::ValuesConstraint<std::string> methodNames(methods);
	TCLAP::ValueArg<std::string> demosaic(
		"", "demosaic", "bilinear (the SDK's), edge-aware (OpenCV's: fewer colour fringes) or half (half resolution, one pixel per Bayer cell: no interpolated colour; intrinsics halved); docs/datasets.md", false,
		"bilinear", &methodNames, cmd);
	TCLAP::ValueArg<std::string> crop("", "crop", "keep X,Y,W,H of the rectified images [px] (principal points follow)", false, "", "X,Y,W,H", cmd);
	CommonArgs common(cli);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	if (noGt.getValue() == extr.isSet())
		return cli.usageError("give --extrinsics DIR (ground truth from gps/ins.csv) or --no-ground-truth");
	RobotCarImporter imp;
	if (crop.isSet())
	{
		std::string why;
		const auto r = parseCrop(crop.getValue(), why);
		if (!r) return cli.usageError(why);
		imp.crop = *r;
	}
	if (origin.isSet())
	{
		std::string why;
		const auto o = parseNumbers(origin.getValue(), 3, "--gt-origin", why);
		if (!o) return cli.usageError(why);
		if (noGt.getValue()) return cli.usageError("--gt-origin goes with the ground truth (not with --no-ground-truth)");
		imp.groundTruthOrigin = Eigen::Vector3d((*o)[0], (*o)[1], (*o)[2]);
	}
	imp.options = common.options();
	imp.modelsDir = models.getValue();
	imp.extrinsicsDir = extr.getValue();
	imp.groundTruth = !noGt.getValue();
	imp.firstFrame = first.getValue();
	imp.stride = stride.getValue();
	imp.demosaic = demosaic.getValue() == "half"		  ? TDemosaic::HalfResolution
				   : demosaic.getValue() == "edge-aware" ? TDemosaic::EdgeAware
														 : TDemosaic::Bilinear;
	common.setup(imp);
	report(imp.run(root.getValue(), common.out.getValue()));
	return 0;
}

int run(int argc, char** argv)
{
	static const std::pair<const char*, int (*)(int, char**)> kinds[] = {
		{"kitti", runKitti}, {"middlebury", runMiddlebury}, {"folder", runFolder}, {"robotcar", runRobotCar}};
	auto usage = [&](std::ostream& o) {
		o << "usage: shadyloc import <kind> [options]   (shadyloc import <kind> --help)\nkinds:\n"
			 "  kitti ROOT --sequence NN -o out.rawlog     KITTI odometry, colour cameras\n"
			 "  middlebury SCENE_DIR -o out.rawlog          Middlebury 2014 scene\n"
			 "  folder --left DIR --right DIR --calib calib.ini -o out.rawlog (--rate HZ | --times FILE)\n"
			 "  robotcar TRAVERSAL -m MODELS (-e EXTRINSICS | --no-ground-truth) -o out.rawlog   Oxford RobotCar\n";
	};
	if (argc >= 2 && !std::strcmp(argv[1], "--version"))
	{
		std::cout << argv[0] << " " << shadyloc::apps::version() << "\n";
		return 0;
	}
	if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))
	{
		usage(argc < 2 ? std::cerr : std::cout);
		return argc < 2 ? 2 : 0;
	}
	for (const auto& [name, fn] : kinds)
		if (!std::strcmp(argv[1], name))
		{
			std::string argv0 = std::string(argv[0]) + " " + name;
			argv[1] = argv0.data();
			return fn(argc - 1, argv + 1);
		}
	std::cerr << "shadyloc import: unknown kind '" << argv[1] << "'\n";
	usage(std::cerr);
	return 2;
}

shadyloc::apps::RegisterCommand reg(
	"import", {"KITTI / Middlebury / image folders / RobotCar -> stereo rawlog (import <kind> --help)", run});
}  // namespace cmd_import
