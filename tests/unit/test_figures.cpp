/* The paper's Figures 7-9 (eval/Figures.h, docs/figures.md): frames.csv
 * reading, blind episodes from it, and the PNGs gnuplot draws. */
#include "../support/TestSupport.h"

#include <shadyloc/eval/Figures.h>

#include <opencv2/imgcodecs.hpp>

#include <array>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

using namespace shadyloc::eval;

namespace
{
const std::string kHeader =
	"frame,stamp,distance_m,in_map,mono_ok,invariant_ok,used,kf_run,kf_frame,kf_id,kf_stamp,mono_inliers,"
	"invariant_inliers,rel_x,rel_y,rel_z,rel_qx,rel_qy,rel_qz,rel_qw";

/** One synthetic frames.csv row: who had a fix and who was used. */
struct TRow
{
	double dist;
	bool inMap;
	int monoOk, invOk;	// -1: that localiser did not run
	std::string used;
};

std::string flag(int v) { return v < 0 ? "" : std::to_string(v); }

/** Writes a frames.csv in localise's layout (the columns the figures do not
 * read are left empty or filled as localise fills them); with `gtDist` a
 * gt_distance_m column of twice the VO distance. */
void writeFrames(const std::string& path, const std::vector<TRow>& rows, bool gtDist = false)
{
	std::ofstream f(path);
	f << kHeader << (gtDist ? ",gt_distance_m,used_true,used_err_m,used_err_deg" : "") << "\n";
	for (size_t i = 0; i < rows.size(); i++)
	{
		const auto& r = rows[i];
		const bool fix = r.used != "none";
		f << i << ',' << 100.0 + 0.1 * i << ',' << r.dist << ',' << int(r.inMap) << ',' << flag(r.monoOk) << ','
		  << flag(r.invOk) << ',' << r.used << ',' << (fix ? "noon,3,1,100.3" : ",,,") << ",50,20,"
		  << (fix ? "0.1,0,0.2,0,0,0,1" : ",,,,,,");
		if (gtDist) f << ',' << 2 * r.dist << ',' << (fix ? "1" : "") << ',' << (fix ? "0.01,0.1" : ",");
		f << '\n';
	}
}

/** A baseline and a combined run of `n` frames 1 m apart: `base(i)` the
 * baseline run has a fix, `inv(i)` the combined run's invariant localiser
 * has one (the combined run then uses mono where the baseline had one). */
void writePair(
	const std::string& dir, int n, const std::function<bool(int)>& base, const std::function<bool(int)>& inv,
	const std::function<bool(int)>& inMap = [](int) { return true; })
{
	std::vector<TRow> b, c;
	for (int i = 0; i < n; i++)
	{
		b.push_back({double(i), inMap(i), base(i), -1, base(i) ? "mono" : "none"});
		c.push_back({double(i), inMap(i), base(i), inv(i), base(i) ? "mono" : (inv(i) ? "invariant" : "none")});
	}
	writeFrames(dir + "/base.csv", b);
	writeFrames(dir + "/comb.csv", c);
}

cv::Vec3b bgr(const char* hex)
{
	const unsigned v = std::stoul(std::string(hex + 1), nullptr, 16);
	return {uchar(v & 255), uchar((v >> 8) & 255), uchar(v >> 16)};
}
// The figures' palette (src/eval/Figures.cpp).
const cv::Vec3b kMono = bgr("#1f62c4"), kInv = bgr("#e6820e"), kBoth = bgr("#2e9e44"), kNeither = bgr("#d62728"),
				kOutside = bgr("#dcdcdc");

size_t countColour(const cv::Mat& img, const cv::Vec3b& c, int y0 = 0, int y1 = -1)
{
	size_t n = 0;
	for (int y = y0; y < (y1 < 0 ? img.rows : y1); y++)
		for (int x = 0; x < img.cols; x++) n += img.at<cv::Vec3b>(y, x) == c;
	return n;
}

/** Non-blank: most pixels white, but thousands are not, in many grey levels. */
void expectDrawn(const cv::Mat& img)
{
	size_t nonWhite = 0;
	std::array<bool, 256> levels{};
	for (int y = 0; y < img.rows; y++)
		for (int x = 0; x < img.cols; x++)
		{
			const auto p = img.at<cv::Vec3b>(y, x);
			nonWhite += p != cv::Vec3b(255, 255, 255);
			levels[(p[0] + p[1] + p[2]) / 3] = true;
		}
	const size_t total = size_t(img.rows) * img.cols;
	EXPECT_GT(nonWhite, total / 100) << "nearly blank";
	EXPECT_LT(nonWhite, total / 2) << "mostly filled: no white background?";
	EXPECT_GT(std::count(levels.begin(), levels.end(), true), 20) << "too few grey levels: no text or antialiasing?";
}

std::string thrown(const std::function<void()>& f)
{
	try
	{
		f();
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "(nothing thrown)";
}

bool haveGnuplot() { return shadyloc::test::runCommand("command -v gnuplot >/dev/null") == 0; }
#define REQUIRE_GNUPLOT() \
	ASSERT_TRUE(haveGnuplot()) << "gnuplot is missing: install Debian's gnuplot-nox (scripts/setup.sh does)"
}  // namespace

// ---------------------------------------------------------------- frames.csv

TEST(FiguresCsv, ReadsTheColumnsAndPrefersGroundTruthDistance)
{
	const auto dir = shadyloc::test::tempDir("figures_csv");
	writeFrames(dir + "/vo.csv", {{0, true, 1, 0, "mono"}, {1.5, false, 0, 1, "invariant"}, {2.5, true, 0, -1, "none"}});
	const auto r = readFramesCsv(dir + "/vo.csv");
	ASSERT_EQ(r.frames.size(), 3u);
	EXPECT_FALSE(r.gt_distance);
	EXPECT_EQ(r.frames[1].frame, 1);
	EXPECT_DOUBLE_EQ(r.frames[1].stamp, 100.1);
	EXPECT_DOUBLE_EQ(r.frames[1].distance_m, 1.5);
	EXPECT_FALSE(r.frames[1].in_map);
	EXPECT_EQ(r.frames[1].invariant_ok, 1);
	EXPECT_EQ(r.frames[2].invariant_ok, -1);
	EXPECT_EQ(r.frames[0].used, "mono");
	EXPECT_FALSE(r.frames[2].fix());
	writeFrames(dir + "/gt.csv", {{0, true, 1, 0, "mono"}, {1.5, true, 0, 0, "none"}}, true);
	const auto g = readFramesCsv(dir + "/gt.csv");
	EXPECT_TRUE(g.gt_distance);
	EXPECT_DOUBLE_EQ(g.frames[1].distance_m, 3.0);	// gt_distance_m, not distance_m
	EXPECT_EQ(g.frames[0].used_true, 1);
	EXPECT_EQ(g.frames[1].used_true, -1);
}

TEST(FiguresCsv, BadInputNamesFileLineAndColumn)
{
	const auto dir = shadyloc::test::tempDir("figures_csv_bad");
	auto write = [&](const std::string& name, const std::string& text) {
		std::ofstream(dir + "/" + name) << text;
		return dir + "/" + name;
	};
	const std::string row = "0,100.0,0.0,1,1,0,mono,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n";
	struct Case
	{
		std::string file, text, expect;
	} cases[] = {
		{"nocol.csv", "frame,stamp,in_map,mono_ok,invariant_ok,used\n0,1,1,1,0,mono\n", "line 1: no column 'distance_m'"},
		{"nan.csv", kHeader + "\n" + row + row + "2,100.2,abc,1,1,0,mono,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n",
		 "line 4: column 'distance_m': 'abc' is not a number"},
		{"short.csv", kHeader + "\n" + row + "1,100.1,1.0,1\n", "line 3: 4 fields, the header has 20"},
		{"flag.csv", kHeader + "\n" + "0,100.0,0.0,yes,1,0,mono,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n",
		 "line 2: column 'in_map': 'yes' is not 0 or 1"},
		{"used.csv", kHeader + "\n" + "0,100.0,0.0,1,1,0,both,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n",
		 "line 2: column 'used': 'both' is not mono, invariant, joint or none"},
		{"frame.csv", kHeader + "\n" + "0.5,100.0,0.0,1,1,0,mono,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n",
		 "line 2: column 'frame': '0.5' is not a whole number"},
		{"back.csv", kHeader + "\n" + row + "1,100.1,-2.0,1,1,0,mono,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n",
		 "line 3: the distance travelled decreases"},
		{"empty.csv", "", "line 1: empty file"},
		{"header.csv", kHeader + "\n", "no frames"},
	};
	for (const auto& c : cases)
	{
		const std::string path = write(c.file, c.text);
		const std::string msg = thrown([&] { readFramesCsv(path); });
		EXPECT_NE(msg.find("'" + path + "'"), std::string::npos) << c.file << ": " << msg;
		EXPECT_NE(msg.find(c.expect), std::string::npos) << c.file << ": " << msg;
	}
	EXPECT_NE(thrown([&] { readFramesCsv(dir + "/none.csv"); }).find("none.csv"), std::string::npos);
}

// The episode lengths of a frames.csv follow the one definition
// (eval::blindEpisodes, also eval::evaluate's): from the fix before
// to the fix after, on the ground-truth distance when the file has it; the
// stretches before the first fix and after the last are not "between".
TEST(FiguresCsv, BlindEpisodesFromFramesCsv)
{
	const auto dir = shadyloc::test::tempDir("figures_episodes");
	// fixes at frames 2, 3, 7, 8, 12; frames 1 m apart.
	std::vector<TRow> rows;
	for (int i = 0; i < 15; i++)
	{
		const bool fix = i == 2 || i == 3 || i == 7 || i == 8 || i == 12;
		rows.push_back({double(i), true, int(fix), 0, fix ? "mono" : "none"});
	}
	writeFrames(dir + "/vo.csv", rows);
	writeFrames(dir + "/gt.csv", rows, true);
	const auto vo = readFramesCsv(dir + "/vo.csv");
	const auto ep = blindEpisodesOf(vo);
	ASSERT_EQ(ep.size(), 4u);
	EXPECT_EQ(ep[0].kind, TBlindEpisode::BeforeFirstFix);
	EXPECT_DOUBLE_EQ(ep[0].length_m, 2.0);
	EXPECT_EQ(ep[1].first, 4u);
	EXPECT_EQ(ep[1].last, 6u);
	EXPECT_EQ(ep[3].kind, TBlindEpisode::AtEnd);
	EXPECT_DOUBLE_EQ(ep[3].length_m, 2.0);	// 12 -> 14
	EXPECT_EQ(blindEpisodeLengths(vo), (std::vector<double>{4.0, 4.0}));  // 3 -> 7, 8 -> 12
	EXPECT_EQ(blindEpisodeLengths(readFramesCsv(dir + "/gt.csv")), (std::vector<double>{8.0, 8.0}));
	// Never localised: one episode before the first fix, none between.
	for (auto& r : rows) r.used = "none";
	writeFrames(dir + "/never.csv", rows);
	const auto never = blindEpisodesOf(readFramesCsv(dir + "/never.csv"));
	ASSERT_EQ(never.size(), 1u);
	EXPECT_EQ(never[0].kind, TBlindEpisode::BeforeFirstFix);
	EXPECT_DOUBLE_EQ(never[0].length_m, 14.0);
	EXPECT_THROW(blindEpisodes({true, false}, {0.0}), std::invalid_argument);
}

TEST(FiguresCsv, FixHolderOfTheTwoRuns)
{
	TLocalisedFrame b, c;
	b.used = "mono";
	c.used = "mono", c.invariant_ok = 1;
	EXPECT_EQ(fixHolder(b, c), FixHolder::Both);
	c.invariant_ok = 0;
	EXPECT_EQ(fixHolder(b, c), FixHolder::BaselineOnly);
	b.used = "none", c.invariant_ok = 1, c.used = "invariant";
	EXPECT_EQ(fixHolder(b, c), FixHolder::InvariantOnly);
	c.invariant_ok = 0, c.used = "mono";  // the combined run's mono alone: neither of the two
	EXPECT_EQ(fixHolder(b, c), FixHolder::Neither);
}

// ---------------------------------------------------------------- figures

// Figure 8's bar: each stretch's colour is its holder and its length is its
// distance, so along the bar's middle row the colours' pixel counts are in
// the ratio of the distances (frames 1 m apart; each frame spans half-way to
// its neighbours).
TEST(Figures, Figure8ColoursAreWhoHeldEachStretch)
{
	REQUIRE_GNUPLOT();
	const auto dir = shadyloc::test::tempDir("figures_8");
	writePair(
		dir, 100, [](int i) { return i < 60; }, [](int i) { return i < 40 || (i >= 60 && i < 80); },
		[](int i) { return i < 90; });
	figure8("live_run", {{"noon's map", dir + "/base.csv", dir + "/comb.csv"}}, dir + "/f8.png");
	const cv::Mat img = cv::imread(dir + "/f8.png");
	ASSERT_EQ(img.cols, 1100);
	ASSERT_EQ(img.rows, 200);  // 130 + 45 px a map, at least 200
	expectDrawn(img);
	// The bar's middle row: the row with the most pixels of the four colours.
	int best = -1;
	size_t bestN = 0;
	for (int y = 0; y < img.rows; y++)
	{
		size_t n = 0;
		for (const auto& c : {kMono, kInv, kBoth, kNeither}) n += countColour(img, c, y, y + 1);
		if (n > bestN) bestN = n, best = y;
	}
	ASSERT_GT(bestN, 300u) << "no bar";
	// The bar: the run of non-white pixels from its first coloured one (the
	// legend's swatches to its right are not counted).
	std::map<int, double> along;  // colour index -> pixels
	const cv::Vec3b colours[] = {kBoth, kMono, kInv, kNeither};
	int x = 0;
	while (x < img.cols && std::none_of(std::begin(colours), std::end(colours), [&](const cv::Vec3b& c) {
			   return img.at<cv::Vec3b>(best, x) == c;
		   }))
		x++;
	for (; x < img.cols && img.at<cv::Vec3b>(best, x) != cv::Vec3b(255, 255, 255); x++)
		for (int k = 0; k < 4; k++) along[k] += img.at<cv::Vec3b>(best, x) == colours[k];
	const double both = along[0], base = along[1], inv = along[2], neither = along[3];
	const int barEnd = x;
	// Distances: both 0..39.5, baseline only 39.5..59.5, invariant only
	// 59.5..79.5, neither 79.5..99; 1-2 px of antialiasing at each edge.
	EXPECT_NEAR(base / both, 20.0 / 39.5, 0.03);
	EXPECT_NEAR(inv / both, 20.0 / 39.5, 0.03);
	EXPECT_NEAR(neither / both, 19.5 / 39.5, 0.03);
	// Frames 90-99 lie outside the map: a dark bar under the row, about a
	// tenth of the bar's length.
	size_t outside = 0;
	for (int y = best; y < img.rows; y++)
	{
		size_t n = 0;
		for (int u = 0; u < barEnd; u++) n += img.at<cv::Vec3b>(y, u) == cv::Vec3b(0x60, 0x60, 0x60);
		outside = std::max(outside, n);
	}
	EXPECT_NEAR(double(outside) / (both + base + inv + neither), 9.5 / 99.0, 0.02);
}

TEST(Figures, Figure7MarksFixesAndTheFramesOutsideTheMap)
{
	REQUIRE_GNUPLOT();
	const auto dir = shadyloc::test::tempDir("figures_7");
	writePair(
		dir, 80, [](int i) { return i % 4 != 0 && i < 50; }, [](int i) { return i % 3 == 0; },
		[](int i) { return i < 70; });
	figure7("it's_live", "map_2", dir + "/base.csv", dir + "/comb.csv", dir + "/f7.png");
	const cv::Mat img = cv::imread(dir + "/f7.png");
	ASSERT_EQ(img.cols, 1000);
	ASSERT_EQ(img.rows, 360);
	expectDrawn(img);
	EXPECT_GT(countColour(img, kMono), 300u);
	EXPECT_GT(countColour(img, kInv), 300u);
	EXPECT_GT(countColour(img, kOutside), 2000u) << "frames 70-79 are outside the map";
	// Two runs of different live runs are refused, naming both; nothing written.
	writeFrames(dir + "/short.csv", {{0, true, 1, -1, "mono"}});
	const std::string msg = thrown([&] { figure7("a", "b", dir + "/short.csv", dir + "/comb.csv", dir + "/bad.png"); });
	EXPECT_NE(msg.find("short.csv"), std::string::npos) << msg;
	EXPECT_NE(msg.find("comb.csv"), std::string::npos) << msg;
	EXPECT_NE(msg.find("not the same live run"), std::string::npos) << msg;
	// The combined run as baseline, or the baseline as combined: refused.
	EXPECT_NE(thrown([&] { figure7("a", "b", dir + "/base.csv", dir + "/base.csv", dir + "/bad.png"); })
				  .find("not a combined run"),
			  std::string::npos);
	EXPECT_NE(thrown([&] { figure7("a", "b", dir + "/comb.csv", dir + "/comb.csv", dir + "/bad.png"); })
				  .find("not a baseline run"),
			  std::string::npos);
	// One run with ground truth, the other without: their distances differ.
	writeFrames(dir + "/gt.csv", {{0, true, 1, -1, "mono"}}, true);
	EXPECT_NE(thrown([&] { figure7("a", "b", dir + "/gt.csv", dir + "/comb.csv", dir + "/bad.png"); })
				  .find("was localised with --gt and"),
			  std::string::npos);
	EXPECT_FALSE(std::filesystem::exists(dir + "/bad.png"));
}

// Figure 9: P(episode >= d) is 1 up to the shortest episode and falls by
// 1/N at each episode's length. Baseline episodes of 10, 20, 30 and 40 m:
// the blue curve runs level at P = 0.75, 0.5 and 0.25 for 10 m each, and at
// P = 1 from 5 to 10 m, where the combined run's one episode of 5 m (green,
// drawn over it from 0 to 5 m) has dropped to 0. The y axis (the longest dark
// vertical line, from P = 0 to the top of the range, 1.05) gives the rows.
TEST(Figures, Figure9DrawsBothDistributions)
{
	REQUIRE_GNUPLOT();
	const auto dir = shadyloc::test::tempDir("figures_9");
	figure9({10, 20, 30, 40}, {5}, dir + "/f9.png");
	const cv::Mat img = cv::imread(dir + "/f9.png");
	ASSERT_EQ(img.cols, 800);
	ASSERT_EQ(img.rows, 500);
	expectDrawn(img);
	int axisX = -1, axisTop = 0, axisBottom = 0, longest = 0;
	for (int x = 0; x < img.cols / 3; x++)
		for (int y = 0, run = 0; y < img.rows; y++)
		{
			const auto p = img.at<cv::Vec3b>(y, x);
			run = p[0] < 100 && p[1] < 100 && p[2] < 100 ? run + 1 : 0;
			if (run > longest) longest = run, axisX = x, axisBottom = y, axisTop = y - run + 1;
		}
	ASSERT_GT(longest, 300) << "no y axis";
	auto rowOf = [&](double P) { return int(std::lround(axisBottom - P / 1.05 * (axisBottom - axisTop))); };
	// The most pixels of colour c on a row within 2 px of P's row, right of the axis.
	auto level = [&](const cv::Vec3b& c, double P) {
		size_t most = 0;
		for (int y = rowOf(P) - 2; y <= rowOf(P) + 2; y++)
		{
			size_t n = 0;
			for (int x = axisX + 1; x < img.cols; x++) n += img.at<cv::Vec3b>(y, x) == c;
			most = std::max(most, n);
		}
		return double(most);
	};
	const double tenMetres = level(kMono, 0.75);
	EXPECT_GT(tenMetres, 100);	// 10 m of a 42 m axis over ~700 px
	EXPECT_NEAR(level(kMono, 0.5) / tenMetres, 1.0, 0.05);
	EXPECT_NEAR(level(kMono, 0.25) / tenMetres, 1.0, 0.05);
	EXPECT_NEAR(level(kMono, 1.0) / tenMetres, 0.5, 0.05);
	EXPECT_NEAR(level(kBoth, 1.0) / tenMetres, 0.5, 0.05);
	EXPECT_LT(level(kBoth, 0.5), 10) << "the combined curve crosses P = 0.5 only in its drop";
	EXPECT_LT(level(kMono, 0.9), 10);
	// No episodes at all still draws (the legend says so); bad lengths do not.
	figure9({}, {}, dir + "/empty.png");
	EXPECT_EQ(cv::imread(dir + "/empty.png").cols, 800);
	EXPECT_THROW(figure9({-1.0}, {}, dir + "/bad.png"), std::invalid_argument);
	EXPECT_FALSE(std::filesystem::exists(dir + "/bad.png"));
}

TEST(Figures, GnuplotErrorsAreReportedAndLeaveNoFile)
{
	REQUIRE_GNUPLOT();
	const auto dir = shadyloc::test::tempDir("figures_gp");
	EXPECT_EQ(gnuplotQuote("it's"), "'it''s'");
	const std::string msg = thrown([&] { runGnuplot("plot $nosuchblock using 1:2", dir + "/x.png", 100, 100); });
	EXPECT_NE(msg.find("gnuplot failed drawing '" + dir + "/x.png'"), std::string::npos) << msg;
	EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
	runGnuplot("plot x", dir + "/ok.png", 120, 90);
	const cv::Mat ok = cv::imread(dir + "/ok.png");
	EXPECT_EQ(ok.cols, 120);
	EXPECT_EQ(ok.rows, 90);
}

// ---------------------------------------------------------------- the command

TEST(FiguresApp, DrawsAllThreeFromLocaliseFoldersOrNothing)
{
	REQUIRE_GNUPLOT();
	const auto dir = shadyloc::test::tempDir("figures_app");
	for (const std::string m : {"mapA", "mapB"})
	{
		std::filesystem::create_directories(dir + "/" + m + "_b");
		std::filesystem::create_directories(dir + "/" + m + "_c");
		writePair(
			dir, 50, [&](int i) { return m == "mapA" ? i % 10 < 6 : i % 10 < 3; }, [](int i) { return i % 10 < 8; });
		std::filesystem::rename(dir + "/base.csv", dir + "/" + m + "_b/frames.csv");
		std::filesystem::rename(dir + "/comb.csv", dir + "/" + m + "_c/frames.csv");
	}
	std::filesystem::create_directories(dir + "/out");
	const std::string app = shadyloc::test::appPath() + " figures ";
	const std::string pairs = " -p live,mapA," + dir + "/mapA_b," + dir + "/mapA_c -p live,mapB," + dir + "/mapB_b," +
							  dir + "/mapB_c ";
	std::string out;
	ASSERT_EQ(shadyloc::test::runCommand(app + pairs + "--fig7 live,mapB -o " + dir + "/out", &out), 0) << out;
	EXPECT_NE(out.find("live against mapA: 4 baseline and 4 combined blind episodes"), std::string::npos) << out;
	EXPECT_EQ(cv::imread(dir + "/out/figure7.png").cols, 1000);
	EXPECT_EQ(cv::imread(dir + "/out/figure8.png").rows, 130 + 2 * 45);
	EXPECT_EQ(cv::imread(dir + "/out/figure9.png").cols, 800);
	// A bad frames.csv: an error naming it and its line; no figure written,
	// the earlier ones kept (all outputs or none).
	std::filesystem::create_directories(dir + "/out2");
	{
		std::ofstream f(dir + "/mapB_c/frames.csv", std::ios::app);
		f << "50,105.0,50.0,1,1,x,mono,noon,3,1,100.3,50,20,0.1,0,0.2,0,0,0,1\n";
	}
	EXPECT_NE(shadyloc::test::runCommand(app + pairs + "-o " + dir + "/out2", &out), 0);
	EXPECT_NE(out.find(dir + "/mapB_c/frames.csv' line 52: column 'invariant_ok': 'x' is not 0 or 1"), std::string::npos)
		<< out;
	EXPECT_TRUE(std::filesystem::is_empty(dir + "/out2"));
	// Options naming what is not there.
	EXPECT_NE(shadyloc::test::runCommand(app + pairs + "--fig7 live,mapC -o " + dir + "/out2", &out), 0);
	EXPECT_NE(out.find("--fig7 'live,mapC': no --pair"), std::string::npos) << out;
	EXPECT_NE(shadyloc::test::runCommand(app + "-p live,mapA," + dir + "/nowhere," + dir + "/mapA_c -o " + dir + "/out2", &out), 0);
	EXPECT_NE(out.find("nowhere/frames.csv' does not exist"), std::string::npos) << out;
	EXPECT_NE(shadyloc::test::runCommand(app + "-p live,mapA -o " + dir + "/out2", &out), 0);
	EXPECT_NE(out.find("expected LIVE,MAP,BASELINE_DIR,COMBINED_DIR"), std::string::npos) << out;
	EXPECT_TRUE(std::filesystem::is_empty(dir + "/out2"));
}
