/* Command-line parsing in every subcommand: a parse error is a message and a
 * non-zero exit, never a run with a default; numbers are parsed strictly. */
#include "../support/TestSupport.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <regex>
#include <sstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
struct CliCase
{
	std::string args;	 //!< after "shadyloc "
	std::string expect;	 //!< in the message (the option at fault)
};

void expectCliRefused(const std::vector<CliCase>& cases, const std::string& mustNotExist)
{
	for (const auto& c : cases)
	{
		std::string out;
		const int rc = test::runCommand(test::appPath() + " " + c.args, &out);
		EXPECT_NE(rc, 0) << c.args << "\n" << out;
		EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << ": message lacks '" << c.expect << "'\n" << out;
		if (!mustNotExist.empty())
		{
			EXPECT_FALSE(fs::exists(mustNotExist)) << c.args;
		}
		fs::remove_all(mustNotExist);
	}
}
}  // namespace

TEST(CommandLine, ImageRefusesBadNumbersAndUnknownFlags)
{
	const auto dir = test::tempDir("cli_image");
	cv::Mat img(20, 30, CV_8UC3, cv::Scalar(60, 90, 120));
	ASSERT_TRUE(cv::imwrite(dir + "/in.png", img));
	const std::string io = "image " + dir + "/in.png " + dir + "/out.png";
	expectCliRefused(
		{{io + " --alpha nan", "alpha"},
		 {io + " --alpha inf", "alpha"},
		 {io + " --alpha 1e999", "alpha"},
		 {io + " --alpha 0.5abc", "alpha"},
		 {io + " --alpha ''", "alpha"},
		 {io + " --beta abc", "beta"},
		 {io + " --gamma -nan", "gamma"},
		 {io + " --scale 0x10", "scale"},
		 {io + " --no-such-flag", "no-such-flag"},
		 {io + " --channel mono --alpha", "alpha"}},
		dir + "/out.png");
}

TEST(CommandLine, SimRefusesBadFrameCountsBeforeRendering)
{
	const auto dir = test::tempDir("cli_sim");
	// A small copy of the default config: two frames per traversal, so a run
	// that ignored the error would be quick (and would leave rawlogs).
	std::ifstream in(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	std::stringstream s;
	s << in.rdbuf();
	const std::string ini = std::regex_replace(s.str(), std::regex("(frames|end_s_m) = [0-9]+"), "frames = 2");
	std::ofstream(dir + "/sim.ini") << ini;
	const std::string sim = "sim -q -c " + dir + "/sim.ini -o " + dir + "/out";
	expectCliRefused(
		{{sim + " --frames abc", "frames"},
		 {sim + " --frames 2.5", "frames"},
		 {sim + " --frames 99999999999", "frames"},
		 {sim + " --frames -3", "frames"},
		 {sim + " --sheet-frames 1e3", "sheet-frames"},
		 {sim + " --start-s nan", "start-s"},
		 {sim + " --bogus", "bogus"}},
		dir + "/out");
}

TEST(CommandLine, EveryCommandRefusesUnknownFlagsAndBadNumbers)
{
	const auto dir = test::tempDir("cli_all");
	test::writeSyntheticRawlog(dir + "/r.rawlog", 2, false);
	std::ofstream(dir + "/t.tum") << "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n3 2 0 0 0 0 0 1\n";
	const std::string r = dir + "/r.rawlog", t = dir + "/t.tum", o = dir + "/o";
	expectCliRefused(
		{{"vo -i " + r + " -o " + o + " --frobnicate", "frobnicate"},
		 {"filter -i " + r + " -o " + o + " --frobnicate", "frobnicate"},
		 {"traj-error --gt " + t + " --est " + t + " --max-dt nan", "max-dt"},
		 {"traj-error --gt " + t + " --est " + t + " --max-dt -1", "max-dt"},
		 {"traj-error --gt " + t + " --est " + t + " --frobnicate", "frobnicate"},
		 {"render -t " + t + " -o " + o + " --width -1", "width"},
		 {"render -t " + t + " -o " + o + " --width 4294967297", "width"},
		 {"render -t " + t + " -o " + o + " --height 12x", "height"},
		 {"export kitti -i " + r + " -o " + o + " --gt-tolerance nan", "gt-tolerance"},
		 {"export kitti -i " + r + " -o " + o + " --frobnicate", "frobnicate"},
		 {"import folder --left " + dir + " --right " + dir + " --calib x.ini --rate 10 -o " + o + " --max-frames -1",
		  "max-frames"},
		 {"import folder --left " + dir + " --right " + dir + " --calib x.ini --rate inf -o " + o, "rate"},
		 {"import middlebury " + dir + " -o " + o + " --timestamp abc", "timestamp"},
		 {"import robotcar " + dir + " -m " + dir + " --no-ground-truth -o " + o + " --first-frame -3", "first-frame"}},
		o);
}

TEST(CommandLine, HelpAndVersionExitZero)
{
	for (const char* c : {"image", "vo", "filter", "sim", "traj-error", "render", "render-traj", "survey", "map-info", "localise", "eval", "calibrate-alpha", "figures", "export kitti",
								"import kitti", "import folder", "import middlebury", "import robotcar"})
	{
		std::string out;
		EXPECT_EQ(test::runCommand(test::appPath() + " " + c + " --help", &out), 0) << c << "\n" << out;
		EXPECT_NE(out.find("--"), std::string::npos) << c << " --help printed no options\n" << out;
		EXPECT_EQ(test::runCommand(test::appPath() + " " + c + " --version", &out), 0) << c << "\n" << out;
	}
	std::string out;
	EXPECT_EQ(test::runCommand(test::appPath() + " --version", &out), 0) << out;
	// The commit the program was built from (cmake/WriteCommit.cmake): a
	// hexadecimal hash, or "unknown" outside git.
	EXPECT_TRUE(std::regex_search(out, std::regex("\\(commit ([0-9a-f]{12}(-dirty)?|unknown)\\)"))) << out;
}
