/* ShadyLoc tests: settings are read strictly and every options struct's dump
 * loads back to the same values. */
#include <shadyloc/core/Settings.h>
#include <shadyloc/datasets/Folder.h>
#include <shadyloc/datasets/Kitti.h>
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/vo/StereoVO.h>
#include <shadyloc/vo/VOConfig.h>

#include "../support/TestSupport.h"

#include <gtest/gtest.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <charconv>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>

using namespace shadyloc;

namespace
{
/** Runs load, expects it to throw, and the message to contain every part. */
void expectRefused(
	const std::function<void()>& load, const std::vector<std::string>& mustContain, const std::string& what)
{
	try
	{
		load();
		ADD_FAILURE() << what << ": accepted";
	}
	catch (const std::exception& e)
	{
		for (const auto& m : mustContain)
			EXPECT_NE(std::string(e.what()).find(m), std::string::npos)
				<< what << ": message '" << e.what() << "' lacks '" << m << "'";
	}
}
}  // namespace

// Regression: TStereoVOOptions::dumpToTextStream wrote "two_view_ba = true ;
// comment", which MRPT read back as false (its bool reader does not strip the
// comment); ransac_prediction likewise. A dump must load back to the same options.
TEST(Settings, VOOptionsDumpLoadsBackIdentically)
{
	vo::TStereoVOOptions o;
	ASSERT_TRUE(o.two_view_ba);
	ASSERT_TRUE(o.ransac_prediction);
	std::ostringstream dump;
	o.dumpToTextStream(dump);
	mrpt::config::CConfigFileMemory c("[vo]\n" + dump.str());
	vo::TStereoVOOptions back;
	back.loadFromConfigFile(c, "vo");
	EXPECT_TRUE(back.two_view_ba) << dump.str();
	EXPECT_TRUE(back.ransac_prediction) << dump.str();
	EXPECT_TRUE(back.constant_velocity) << dump.str();
	std::ostringstream again;
	back.dumpToTextStream(again);
	EXPECT_EQ(again.str(), dump.str());
}

// Regression (issue 9, fault 5): config values silently became other numbers.
TEST(Settings, FeatureNumbersOutOfRangeOrNotNumbersAreRefused)
{
	auto load = [](const std::string& line) {
		return [line] {
			mrpt::config::CConfigFileMemory c("[features]\n" + line + "\n");
			features::TStereoFeatureOptions o;
			o.loadFromConfigFile(c, "features");
		};
	};
	for (const char* line :
		 {"fast_threshold = 1e308", "fast_threshold = 12.5", "fast_threshold = abc",
		  "max_per_cell = 2147483648", "max_per_cell = 4294967308", "max_per_cell = -2147483649",
		  "brief_seed = 4294967296", "brief_seed = -1", "sigma_px = nan", "sigma_px = inf",
		  "max_depth = 1e400", "min_zncc = 0.8x", "dense_check = maybe", "dense_check = 2"})
	{
		const std::string l(line);
		expectRefused(load(l), {"[features]", l.substr(0, l.find(' '))}, l);
	}
}

TEST(Settings, VONumbersOutOfRangeOrNotNumbersAreRefused)
{
	auto load = [](const std::string& line) {
		return [line] {
			mrpt::config::CConfigFileMemory c("[vo]\n" + line + "\n");
			vo::TStereoVOOptions o;
			o.loadFromConfigFile(c, "vo");
		};
	};
	for (const char* line :
		 {"kf_rotation_deg = inf", "max_lost_frames = 4294967299", "ransac_iterations = 1e308",
		  "huber_k = 1.0.0", "two_view_ba = ja", "max_step_rotation_deg = 30 deg"})
	{
		const std::string l(line);
		expectRefused(load(l), {"[vo]", l.substr(0, l.find(' '))}, l);
	}
}

TEST(Settings, FilterNumbersThatAreTextAreRefused)
{
	auto load = [](const std::string& line) {
		return [line] {
			mrpt::config::CConfigFileMemory c(
				"[filters]\npipeline = inv\n[inv]\nclass = CFilterInvariant\n" + line + "\n");
			filters::FilterPipeline::FromConfig(c, "test.ini");
		};
	};
	for (const char* line :
		 {"beta = abc", "alpha = 0.4.8", "scale = 1e999", "offset = nan", "parallel_eyes = yes please"})
	{
		const std::string l(line);
		expectRefused(load(l), {"test.ini", "[inv]", l.substr(0, l.find(' '))}, l);
	}
}

// ---- the reader itself --------------------------------------------------------
namespace
{
/** Reads `value` as [s] k into v through the strict reader. */
template <typename T>
void readOne(const std::string& value, T& v)
{
	mrpt::config::CConfigFileMemory c("[s]\nk = " + value + "\n");
	core::SettingsSection r(c, "s");
	r.read("k", v);
	r.finish();
}
template <typename T>
void expectValueRefused(const std::string& value)
{
	T v{};
	expectRefused([&] { readOne(value, v); }, {"[s] k", "'" + value.substr(0, value.find_first_of(";#")) }, value);
}
}  // namespace

TEST(Settings, IntegersMustBeWholeAndFitTheirType)
{
	for (const char* bad : {"1e308", "2147483648", "4294967308", "-2147483649", "abc", "nan", "inf", "12.5",
							"1e3", "12 13", "0x", "--1", "9223372036854775808", ""})
		expectValueRefused<int>(bad);
	for (const char* bad : {"4294967296", "-1", "1e9", "0x100000000"}) expectValueRefused<uint32_t>(bad);
	const std::vector<std::pair<std::string, int>> good = {
		{"-2147483648", std::numeric_limits<int>::min()}, {"2147483647", 2147483647}, {"+5", 5},
		{"0x10", 16}, {"-0", 0}, {"7 ; seven", 7}, {"7 # seven", 7}, {"-12", -12}};
	for (const auto& [t, want] : good)
	{
		int v = 99;
		readOne(t, v);
		EXPECT_EQ(v, want) << t;
	}
	uint32_t u = 0;
	readOne("4294967295", u);
	EXPECT_EQ(u, 4294967295u);
	readOne("0x5ad710c", u);
	EXPECT_EQ(u, 0x5ad710cu);
	size_t z = 0;
	readOne("18446744073709551615", z);
	EXPECT_EQ(z, std::numeric_limits<size_t>::max());
}

TEST(Settings, RealsMustParseCompletelyAndBeFinite)
{
	for (const char* bad : {"abc", "nan", "NaN", "inf", "-inf", "infinity", "1e309", "-1e400", "1.5x", "0.4.8",
							"1,5", "", "0x1p3", "30 deg"})
		expectValueRefused<double>(bad);
	expectValueRefused<float>("1e39");
	const std::vector<std::pair<std::string, double>> good = {
		{"-0.5", -0.5}, {"+2", 2.0}, {".5", 0.5}, {"1e-3", 1e-3}, {"1e308", 1e308}, {"3 ; three", 3.0},
		{"0.30000000000000004", 0.1 + 0.2}};
	for (const auto& [t, want] : good)
	{
		double v = 99;
		readOne(t, v);
		EXPECT_EQ(v, want) << t;
	}
}

TEST(Settings, BooleansAreStrictAndCommentsAreStripped)
{
	for (const auto& [t, want] : std::vector<std::pair<std::string, bool>>{
			 {"true", true}, {"True", true}, {"1", true}, {"yes", true}, {"false", false},
			 {"FALSE", false}, {"0", false}, {"no", false}, {"true ; comment", true},
			 {"true   # comment", true}, {"false;x", false}})
	{
		bool v = !want;
		readOne(t, v);
		EXPECT_EQ(v, want) << t;
	}
	for (const char* bad : {"2", "maybe", "ja", "on", "", "true false", "-1"}) expectValueRefused<bool>(bad);
	std::string txt;
	readOne("  a b  ; comment", txt);
	EXPECT_EQ(txt, "a b");
}

TEST(Settings, ChoicesComeFromTheirSet)
{
	mrpt::config::CConfigFileMemory c("[s]\norder = RGB ; any case\nlin = log\n");
	core::SettingsSection r(c, "s");
	image::ChannelOrder o = image::ChannelOrder::BGR;
	r.readChoice("order", o, {{"bgr", image::ChannelOrder::BGR}, {"rgb", image::ChannelOrder::RGB}});
	EXPECT_EQ(o, image::ChannelOrder::RGB);
	std::string lin = "none";
	expectRefused([&] { r.readChoice("lin", lin, {"none", "srgb", "gamma"}); }, {"[s] lin", "'log'", "none | srgb | gamma"}, "lin = log");
}

TEST(Settings, UnknownKeyIsAnErrorNamingFileSectionAndKey)
{
	const std::string path = test::tempDir("settings_unknown") + "/vo.ini";
	std::ofstream(path) << "[vo]\nmax_hamming = 80\nkf_rotaton_deg = 5\n";
	mrpt::config::CConfigFile c(path);
	vo::TStereoVOOptions o;
	expectRefused([&] { o.loadFromConfigFile(c, "vo"); },
				  {path, "[vo] kf_rotaton_deg", "unknown key", "did you mean 'kf_rotation_deg'"}, "typo");
	// Far from every known key: the known ones are listed instead.
	mrpt::config::CConfigFileMemory m("[features]\nwibble = 1\n");
	features::TStereoFeatureOptions f;
	expectRefused([&] { f.loadFromConfigFile(m, "features"); },
				  {"[features] wibble", "unknown key", "known:", "fast_threshold"}, "wibble");
	// Keys differ by case only: MRPT would read it, the style says snake_case.
	mrpt::config::CConfigFileMemory k("[vo]\nTwo_View_BA = false\n");
	expectRefused([&] { o.loadFromConfigFile(k, "vo"); }, {"[vo] Two_View_BA", "two_view_ba"}, "case");
}

TEST(Settings, UnknownKeysAreErrorsInEveryOptionsSection)
{
	const std::string dir = test::tempDir("settings_unknown_all");
	auto file = [&](const std::string& name, const std::string& text) {
		const std::string p = dir + "/" + name;
		std::ofstream(p) << text;
		return p;
	};
	{
		const auto p = file("f.ini", "[filters]\npipeline = inv\n[inv]\nclass = CFilterInvariant\nalpah = 0.5\n");
		expectRefused([&] { filters::FilterPipeline::FromConfigFile(p); }, {p, "[inv] alpah", "did you mean 'alpha'"}, "filter");
	}
	{
		const auto p = file("f2.ini", "[filters]\npipeline = m\npipline = m\n[m]\nclass = CFilterMonochrome\n");
		expectRefused([&] { filters::FilterPipeline::FromConfigFile(p); }, {p, "[filters] pipline"}, "pipeline typo");
	}
	{
		const auto p = file("f3.ini", "[filters]\npipeline = l\n[l]\nclass = CFilterLinearise\nsensor_label = CAM\n");
		expectRefused([&] { filters::FilterPipeline::FromConfigFile(p); }, {p, "[l] sensor_label", "sensor_labels"}, "linearise");
	}
	{
		const auto p = file("c.ini", "[left]\nfx_px=1\nfy_px=1\ncx_px=1\ncy_px=1\nskew=0\n[stereo]\nbaseline_m=0.1\nwidth_px=4\nheight_px=4\n");
		expectRefused([&] { datasets::TFolderCalib::FromFile(p); }, {p, "[left] skew", "unknown key"}, "calib");
	}
	{
		std::ifstream in(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
		std::stringstream ss;
		ss << in.rdbuf();
		std::string t = ss.str();
		t.replace(t.find("\nspeed_mps = 8.5"), 16, "\nspeed_m_s = 8.5");
		const auto p = file("sim.ini", t);
		expectRefused([&] { sim::TSimOptions::FromFile(p); }, {p, "[traversal.noon] speed_m_s", "did you mean 'speed_mps'"}, "sim");
	}
	mrpt::config::CConfigFileMemory imp("[import]\nsensor_label = X\nmax_frame = 3\n");
	datasets::TImportOptions io;
	expectRefused([&] { io.loadFromConfigFile(imp, "import"); }, {"[import] max_frame", "max_frames"}, "import");
	mrpt::config::CConfigFileMemory kit("[export]\nsequense = 01\n");
	datasets::KittiExporter::TOptions ko;
	expectRefused([&] { ko.loadFromConfigFile(kit, "export"); }, {"[export] sequense", "sequence"}, "kitti");
	mrpt::config::CConfigFileMemory inv("[invariant]\nalpha = 0.4\nbeta = 0.6\nscael = 3\n");
	image::InvariantParams ip;
	expectRefused([&] { ip.loadFromConfigFile(inv, "invariant"); }, {"[invariant] scael", "scale"}, "invariant");
}

TEST(Settings, MisspeltSectionIsAnError)
{
	const std::string dir = test::tempDir("settings_sections");
	{
		const std::string p = dir + "/vo.ini";
		std::ofstream(p) << "[vo]\nmax_hamming = 80\n[feature]\nfast_threshold = 5\n";
		mrpt::config::CConfigFile c(p);
		expectRefused([&] { vo::checkVOConfigSections(c); }, {p, "[feature]", "unknown section", "did you mean [features]"}, "vo");
		// ... and the command refuses it before reading anything else.
		std::string out;
		EXPECT_NE(test::runCommand(test::appPath() + " vo -q -i " + dir + "/none.rawlog -c " + p + " -o " + dir + "/t.tum", &out), 0);
		EXPECT_NE(out.find("[feature]: unknown section"), std::string::npos) << out;
		EXPECT_FALSE(std::filesystem::exists(dir + "/t.tum"));
	}
	{
		const std::string p = dir + "/filters.ini";
		std::ofstream(p) << "[filters]\npipeline = mono\n[mono]\nclass = CFilterMonochrome\n[invarient]\nclass = CFilterInvariant\n";
		expectRefused([&] { filters::FilterPipeline::FromConfigFile(p); }, {p, "[invarient]", "unknown section", "pipeline"}, "filters");
	}
	{
		const std::string p = dir + "/calib.ini";
		std::ofstream(p) << "[left]\nfx_px=1\nfy_px=1\ncx_px=1\ncy_px=1\n[rigth]\ncx_px=2\n[stereo]\nbaseline_m=0.1\nwidth_px=4\nheight_px=4\n";
		expectRefused([&] { datasets::TFolderCalib::FromFile(p); }, {p, "[rigth]", "did you mean [right]"}, "calib");
	}
	{
		std::ifstream in(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
		std::stringstream ss;
		ss << in.rdbuf();
		std::string t = ss.str();
		t.replace(t.find("[sim.scene]"), 11, "[sim.scenery]");
		const std::string p = dir + "/sim.ini";
		std::ofstream(p) << t;
		expectRefused([&] { sim::TSimOptions::FromFile(p); }, {p, "[sim.scenery]", "did you mean [sim.scene]"}, "sim");
	}
	// A key before any section belongs to none.
	mrpt::config::CConfigFileMemory top("two_view_ba = false\n[vo]\n");
	expectRefused([&] { vo::checkVOConfigSections(top); }, {"two_view_ba", "before any [section]"}, "top");
}

TEST(Settings, RenamedKeysAreRefusedNamingTheNewOne)
{
	auto check = [](const std::string& section, const std::string& oldKey, const std::string& newKey,
					const std::function<void(const mrpt::config::CConfigFileBase&)>& load) {
		mrpt::config::CConfigFileMemory c("[" + section + "]\n" + oldKey + " = 1\n");
		expectRefused([&] { load(c); }, {"[" + section + "] " + oldKey, "renamed to '" + newKey + "'"}, oldKey);
	};
	auto voLoad = [](const mrpt::config::CConfigFileBase& c) { vo::TStereoVOOptions().loadFromConfigFile(c, "vo"); };
	for (const auto& [o, n] : std::vector<std::pair<std::string, std::string>>{
			 {"refine_radius", "refine_radius_px"}, {"near_min_disparity", "near_min_disparity_px"},
			 {"kf_translation", "kf_translation_m"}, {"max_step_translation", "max_step_translation_m"}})
		check("vo", o, n, voLoad);
	auto fLoad = [](const mrpt::config::CConfigFileBase& c) {
		features::TStereoFeatureOptions().loadFromConfigFile(c, "features");
	};
	for (const auto& [o, n] : std::vector<std::pair<std::string, std::string>>{
			 {"min_disparity", "min_disparity_px"}, {"max_disparity", "max_disparity_px"},
			 {"row_tolerance", "row_tolerance_px"}, {"patch_radius", "patch_radius_px"},
			 {"brief_patch_size", "brief_patch_size_px"}, {"max_depth", "max_depth_m"},
			 {"presmooth_sigma", "presmooth_sigma_px"}})
		check("features", o, n, fLoad);
	auto importLoad = [](const mrpt::config::CConfigFileBase& c) {
		datasets::TImportOptions().loadFromConfigFile(c, "import");
	};
	for (const auto& [o, n] : std::vector<std::pair<std::string, std::string>>{
			 {"sensorLabel", "sensor_label"}, {"externalImages", "external_images"},
			 {"maxFrames", "max_frames"}, {"progressEvery", "progress_every"}})
		check("import", o, n, importLoad);
	auto kittiLoad = [](const mrpt::config::CConfigFileBase& c) {
		datasets::KittiExporter::TOptions().loadFromConfigFile(c, "export");
	};
	for (const auto& [o, n] : std::vector<std::pair<std::string, std::string>>{
			 {"sensorLabel", "sensor_label"}, {"groundTruthTum", "ground_truth_tum"},
			 {"gtTimeTolerance", "gt_time_tolerance_s"}, {"absoluteTimes", "absolute_times"},
			 {"progressEvery", "progress_every"}})
		check("export", o, n, kittiLoad);
	auto camLoad = [](const mrpt::config::CConfigFileBase& c) { sim::TSimCameraOptions().loadFromConfigFile(c, "sim.camera"); };
	check("sim.camera", "width", "width_px", camLoad);
	check("sim.camera", "height", "height_px", camLoad);
	auto travLoad = [](const mrpt::config::CConfigFileBase& c) { sim::TTraversal().loadFromConfigFile(c, "t"); };
	check("t", "start_time", "start_time_s", travLoad);
	// The folder calibration (its own sections), through the file loader.
	const std::string dir = test::tempDir("settings_renamed");
	for (const auto& [text, msg] : std::vector<std::pair<std::string, std::string>>{
			 {"[left]\nfx=1\n", "[left] fx: this key was renamed to 'fx_px'"},
			 {"[left]\nfx_px=1\nfy_px=1\ncx_px=1\ncy_px=1\n[right]\ncy=3\n", "[right] cy: this key was renamed to 'cy_px'"},
			 {"[left]\nfx_px=1\nfy_px=1\ncx_px=1\ncy_px=1\n[stereo]\nbaseline_m=1\nwidth=3\n", "[stereo] width: this key was renamed to 'width_px'"}})
	{
		std::ofstream(dir + "/c.ini") << text;
		expectRefused([&] { datasets::TFolderCalib::FromFile(dir + "/c.ini"); }, {dir + "/c.ini", msg}, text);
	}
}

// ---- every options struct: dump -> load -> the same values -------------------
TEST(Settings, VOOptionsRoundTripWithEveryFieldChanged)
{
	vo::TStereoVOOptions o;
	o.search_radius_px = 33.3;
	o.search_radius_lost_px = 77.7;
	o.max_hamming = 71;
	o.match_ratio = 0.1 + 0.2;	// 0.30000000000000004: needs 17 digits
	o.refine_min_zncc = 0.61;
	o.refine_radius = 3;
	o.refine_iterations = 7;
	o.min_stereo = 25;
	o.min_matches = 15;
	o.min_inliers = 11;
	o.near_min_disparity = 2.5;
	o.near_min_matches = 45;
	o.ransac_threshold_px = 3.3;
	o.ransac_iterations = 321;
	o.sigma_px = 0.7;
	o.huber_k = 1.0 / 3.0;
	o.two_view_ba = false;
	o.ransac_prediction = false;
	o.ransac_prior_sigma_m = 0.2;
	o.kf_translation = 1.3;
	o.kf_rotation_deg = 12.5;
	o.kf_min_tracked_fraction = 0.4;
	o.kf_min_inliers = 44;
	o.max_step_translation = 2.2;
	o.max_step_rotation_deg = 33;
	o.max_lost_frames = 5;
	o.constant_velocity = false;
	std::ostringstream dump;
	o.dumpToTextStream(dump);
	mrpt::config::CConfigFileMemory c("[vo]\n" + dump.str());
	vo::TStereoVOOptions b;
	b.loadFromConfigFile(c, "vo");
#define SAME(f) EXPECT_EQ(b.f, o.f) << #f
	SAME(search_radius_px); SAME(search_radius_lost_px); SAME(max_hamming); SAME(match_ratio);
	SAME(refine_min_zncc); SAME(refine_radius); SAME(refine_iterations); SAME(min_stereo);
	SAME(min_matches); SAME(min_inliers); SAME(near_min_disparity); SAME(near_min_matches);
	SAME(ransac_threshold_px); SAME(ransac_iterations); SAME(sigma_px); SAME(huber_k);
	SAME(two_view_ba); SAME(ransac_prediction); SAME(ransac_prior_sigma_m); SAME(kf_translation);
	SAME(kf_rotation_deg); SAME(kf_min_tracked_fraction); SAME(kf_min_inliers);
	SAME(max_step_translation); SAME(max_step_rotation_deg); SAME(max_lost_frames); SAME(constant_velocity);
	// No comment follows a value on its line.
	std::istringstream lines(dump.str());
	for (std::string l; std::getline(lines, l);)
	{
		if (l.empty() || l[0] == ';') continue;	 // a comment line
		EXPECT_EQ(l.find_first_of(";#"), std::string::npos) << l;
	}
}

TEST(Settings, FeatureOptionsRoundTripWithEveryFieldChanged)
{
	features::TStereoFeatureOptions o;
	o.fast_threshold = 17;
	o.grid_cols = 9;
	o.grid_rows = 7;
	o.max_per_cell = 23;
	o.max_per_cell_right = 61;
	o.min_disparity = 1.5;
	o.max_disparity = 90.25;
	o.row_tolerance = 2;
	o.patch_radius = 4;
	o.min_zncc = 0.85;
	o.max_ambiguity = 0.55;
	o.lr_tolerance_px = 1.25;
	o.min_zncc_shifted = 0.35;
	o.brief_patch_size = 30;
	o.brief_seed = 0xdeadbeef;
	o.sigma_px = 0.45;
	o.max_depth = 70.5;
	o.presmooth_sigma = 1.1;
	o.subpixel_iterations = 4;
	o.dense_check = false;
	o.shifted_window_check = false;
	o.shifted_window_margin = 0.15;
	o.descriptor = features::DescriptorKind::Orb;
	o.orb_levels = 5;
	o.orb_scale_factor = 1.35;
	std::ostringstream dump;
	o.dumpToTextStream(dump);
	mrpt::config::CConfigFileMemory c("[features]\n" + dump.str());
	features::TStereoFeatureOptions b;
	b.loadFromConfigFile(c, "features");
	SAME(fast_threshold); SAME(grid_cols); SAME(grid_rows); SAME(max_per_cell); SAME(max_per_cell_right);
	SAME(min_disparity); SAME(max_disparity); SAME(row_tolerance); SAME(patch_radius); SAME(min_zncc);
	SAME(max_ambiguity); SAME(lr_tolerance_px); SAME(min_zncc_shifted); SAME(brief_patch_size);
	SAME(brief_seed); SAME(sigma_px); SAME(max_depth); SAME(presmooth_sigma); SAME(subpixel_iterations);
	SAME(dense_check); SAME(shifted_window_check); SAME(shifted_window_margin);
	SAME(descriptor); SAME(orb_levels); SAME(orb_scale_factor);
	// And the defaults (dense_check and shifted_window_check true) come back too.
	features::TStereoFeatureOptions d, d2;
	std::ostringstream dd;
	d.dumpToTextStream(dd);
	mrpt::config::CConfigFileMemory cd("[features]\n" + dd.str());
	d2.dumpToTextStream(dd);  // (unchanged defaults dump the same)
	d2.loadFromConfigFile(cd, "features");
	EXPECT_TRUE(d2.dense_check);
	EXPECT_TRUE(d2.shifted_window_check);
}

TEST(Settings, InvariantParamsAndFiltersRoundTrip)
{
	image::InvariantParams p = image::InvariantParams::FromWavelengths(455, 535, 615);
	p.order = image::ChannelOrder::RGB;
	p.linearisation = image::Linearisation::Gamma;
	p.gamma = 1.9;
	p.scale = 127.5;
	p.offset = 0.1 + 0.2;
	p.knee_low = 20.0 / 3.0;
	p.knee_high = 241.1;
	p.tail_slope_low = 0.3;
	p.tail_slope_high = 1.0 / 7.0;
	std::ostringstream dump;
	p.dumpToTextStream(dump);
	mrpt::config::CConfigFileMemory c("[invariant]\n" + dump.str());
	image::InvariantParams b;
	b.loadFromConfigFile(c, "invariant");
	EXPECT_EQ(b.alpha, p.alpha);
	EXPECT_EQ(b.beta, p.beta);
	EXPECT_EQ(b.order, p.order);
	EXPECT_EQ(b.linearisation, p.linearisation);
	EXPECT_EQ(b.gamma, p.gamma);
	EXPECT_EQ(b.scale, p.scale);
	EXPECT_EQ(b.offset, p.offset);
	EXPECT_EQ(b.knee_low, p.knee_low);
	EXPECT_EQ(b.knee_high, p.knee_high);
	EXPECT_EQ(b.tail_slope_low, p.tail_slope_low);
	EXPECT_EQ(b.tail_slope_high, p.tail_slope_high);

	// A pipeline of all three filters, every option changed, through its record text.
	filters::FilterPipeline pl;
	auto mono = CFilterMonochrome::Create();
	mono->order = image::ChannelOrder::RGB;
	mono->common.output_suffix = "_m";
	mono->common.sensor_labels = "LEFT, RIGHT";
	auto inv = CFilterInvariant::Create();
	inv->setParams(p);
	inv->parallel_eyes = false;
	auto lin = CFilterLinearise::Create();
	lin->linearisation = image::Linearisation::Gamma;
	lin->gamma = 2.0 / 3.0;
	pl.filters = {mono, inv, lin};
	const std::string ini = pl.asIni();
	mrpt::config::CConfigFileMemory pc(ini);
	const auto back = filters::FilterPipeline::FromConfig(pc, "record");
	ASSERT_EQ(back.filters.size(), 3u);
	EXPECT_EQ(back.asIni(), ini);
	const auto m2 = std::dynamic_pointer_cast<CFilterMonochrome>(back.filters[0]);
	const auto i2 = std::dynamic_pointer_cast<CFilterInvariant>(back.filters[1]);
	const auto l2 = std::dynamic_pointer_cast<CFilterLinearise>(back.filters[2]);
	ASSERT_TRUE(m2 && i2 && l2);
	EXPECT_EQ(m2->order, image::ChannelOrder::RGB);
	EXPECT_EQ(m2->common.output_suffix, "_m");
	EXPECT_EQ(m2->common.sensor_labels, "LEFT, RIGHT");
	EXPECT_EQ(i2->params().alpha, p.alpha);
	EXPECT_EQ(i2->params().offset, p.offset);
	EXPECT_TRUE(i2->params().sameImageAs(p));
	EXPECT_FALSE(i2->parallel_eyes);
	EXPECT_EQ(l2->gamma, 2.0 / 3.0);
	EXPECT_EQ(l2->linearisation, image::Linearisation::Gamma);
}

TEST(Settings, SimAndDatasetOptionsRoundTrip)
{
	auto o = sim::TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	o.camera.width = 320;
	o.camera.hfov_deg = 61.25;
	o.camera.noise = false;
	o.scene.seed = 4000000000u;
	o.scene.markers = {{1.5, -2, 0.25, 0.1 + 0.2}, {3, 4, 5, 0.5}};
	o.traversals[0].start_time = 1700000000.123456;	// sub-ms digits: printed in full
	o.traversals[1].overcast = true;
	std::ostringstream a;
	o.dumpToTextStream(a);
	const std::string path = test::tempDir("settings_sim") + "/dump.ini";
	std::ofstream(path) << a.str();
	const auto o2 = sim::TSimOptions::FromFile(path);
	std::ostringstream b;
	o2.dumpToTextStream(b);
	EXPECT_EQ(a.str(), b.str());
	EXPECT_EQ(o2.camera.width, 320);
	EXPECT_EQ(o2.camera.hfov_deg, 61.25);
	EXPECT_FALSE(o2.camera.noise);
	EXPECT_EQ(o2.scene.seed, 4000000000u);
	ASSERT_EQ(o2.scene.markers.size(), 2u);
	EXPECT_EQ(o2.scene.markers[0][3], 0.1 + 0.2);
	EXPECT_EQ(o2.traversals[0].start_time, 1700000000.123456);
	EXPECT_TRUE(o2.traversals[1].overcast);

	datasets::TFolderCalib cal;
	cal.fx_l = 713.189, cal.fy_l = 713.25, cal.cx_l = 356.021, cal.cy_l = 238.263;
	cal.fx_r = 700.5, cal.fy_r = 701.5, cal.cx_r = 387.361, cal.cy_r = 1.0 / 3.0;
	cal.baseline_m = 0.178089, cal.width = 707, cal.height = 481;
	std::ostringstream cd;
	cal.dumpToTextStream(cd);
	const std::string cpath = test::tempDir("settings_calib") + "/calib.ini";
	std::ofstream(cpath) << cd.str();
	const auto cal2 = datasets::TFolderCalib::FromFile(cpath);
	std::ostringstream cd2;
	cal2.dumpToTextStream(cd2);
	EXPECT_EQ(cd2.str(), cd.str());
	EXPECT_EQ(cal2.cy_r, 1.0 / 3.0);
	EXPECT_EQ(cal2.width, 707u);

	datasets::TImportOptions io;
	io.sensorLabel = "STEREO";
	io.externalImages = true;
	io.maxFrames = 12;
	io.progressEvery = 7;
	std::ostringstream id;
	io.dumpToTextStream(id);
	mrpt::config::CConfigFileMemory ic("[import]\n" + id.str());
	datasets::TImportOptions io2;
	io2.loadFromConfigFile(ic, "import");
	EXPECT_EQ(io2.sensorLabel, "STEREO");
	EXPECT_TRUE(io2.externalImages);
	EXPECT_EQ(io2.maxFrames, 12u);
	EXPECT_EQ(io2.progressEvery, 7u);

	datasets::KittiExporter::TOptions ko;
	ko.sequence = "07";
	ko.sensorLabel = "CAM";
	ko.groundTruthTum = "gt.tum";
	ko.gtTimeTolerance = 0.1 + 0.2;
	ko.absoluteTimes = true;
	ko.progressEvery = 3;
	std::ostringstream kd;
	ko.dumpToTextStream(kd);
	mrpt::config::CConfigFileMemory kc("[export]\n" + kd.str());
	datasets::KittiExporter::TOptions ko2;
	ko2.loadFromConfigFile(kc, "export");
	EXPECT_EQ(ko2.sequence, "07");
	EXPECT_EQ(ko2.sensorLabel, "CAM");
	EXPECT_EQ(ko2.groundTruthTum, "gt.tum");
	EXPECT_EQ(ko2.gtTimeTolerance, 0.1 + 0.2);
	EXPECT_TRUE(ko2.absoluteTimes);
	EXPECT_EQ(ko2.progressEvery, 3u);
}
#undef SAME

TEST(Settings, WriterPrintsDoublesThatReadBackExactly)
{
	// 10^4 doubles spread over every exponent (random bit patterns, finite).
	std::mt19937_64 rng(42);
	int n = 0;
	while (n < 10000)
	{
		const uint64_t bits = rng();
		double x;
		std::memcpy(&x, &bits, sizeof x);
		if (!std::isfinite(x)) continue;
		n++;
		std::ostringstream os;
		core::SettingsWriter w(os);
		w.value("k", x, "a comment");
		mrpt::config::CConfigFileMemory c("[s]\n" + os.str());
		core::SettingsSection r(c, "s");
		double y = 0;
		r.read("k", y);
		ASSERT_EQ(std::memcmp(&x, &y, sizeof x), 0) << os.str();
	}
	// Text that would not read back is refused rather than written.
	std::ostringstream os;
	core::SettingsWriter w(os);
	EXPECT_THROW(w.value("k", std::string("a;b")), std::invalid_argument);
	EXPECT_THROW(w.value("k", std::string(" padded")), std::invalid_argument);
	EXPECT_THROW(w.value("k", std::nan("")), std::invalid_argument);
}

TEST(Settings, KeyGivenTwiceInAFileIsAnError)
{
	// MRPT keeps the last one without a word; an edit gone wrong, usually.
	const std::string p = test::tempDir("settings_twice") + "/vo.ini";
	std::ofstream(p) << "[vo]\ntwo_view_ba = true\n[features]\nfast_threshold = 5\n[vo]\nTwo_View_BA = false ; later\n";
	mrpt::config::CConfigFile c(p);
	expectRefused([&] { vo::checkVOConfigSections(c); }, {p, "[vo] Two_View_BA", "given twice (lines 2 and 6)"}, "twice");
	// The same key in two sections is fine.
	std::ofstream(p) << "[vo]\nsigma_px = 0.5\n[features]\nsigma_px = 0.5\n";
	mrpt::config::CConfigFile ok(p);
	EXPECT_NO_THROW(vo::checkVOConfigSections(ok));
}

TEST(Settings, LayeredConfigFilesOverrideInOrderAndKeepTheirOwnChecks)
{
	// `-c base.ini -c mine.ini`: a later file's key overrides, a section may
	// continue; within one file a key given twice is still an error.
	const std::string d = test::tempDir("settings_layered");
	std::ofstream(d + "/base.ini") << "[localise]\nthreads = 2\nvo_channel = mono\n[vo]\nsigma_px = 0.5\n";
	std::ofstream(d + "/mine.ini") << "[localise]\nthreads = 1\n";
	const std::string text = core::layeredConfigText({d + "/base.ini", d + "/mine.ini"});
	mrpt::config::CConfigFileMemory c(text);
	EXPECT_EQ(c.read_int("localise", "threads", 0), 1);
	EXPECT_EQ(c.read_string("localise", "vo_channel", ""), "mono");
	EXPECT_EQ(c.read_double("vo", "sigma_px", 0), 0.5);
	std::ofstream(d + "/twice.ini") << "[localise]\nthreads = 1\nthreads = 2\n";
	expectRefused(
		[&] { core::layeredConfigText({d + "/base.ini", d + "/twice.ini"}); },
		{d + "/twice.ini", "threads", "given twice (lines 2 and 3)"}, "twice");
	expectRefused([&] { core::layeredConfigText({d + "/missing.ini"}); }, {d + "/missing.ini", "does not exist"}, "missing");
}

TEST(Settings, MapOptionsRoundTripWithEveryFieldChanged)
{
	TKeyframeMapOptions o;
	o.kf_spacing_m = 0.1 + 0.2;	 // needs 17 digits
	o.kf_spacing_deg = 12.5;
	o.landmarks_per_keyframe = 77;
	o.selection_grid_cols = 5;
	o.selection_grid_rows = 3;
	o.compression_level = 4;
	o.index_cell_m = 1.0 / 3.0;
	o.draw_landmarks = true;
	o.draw_landmark_max_depth_m = 22.5;
	o.draw_frame_every_m = 3.75;
	o.landmark_selection = TKeyframeMapOptions::LandmarkSelection::Strongest;
	o.reobservation_window_m = 4.5;
	o.reobservation_radius_px = 12.5;
	o.min_reobservations = 2;
	o.patch_bits = 5;
	std::ostringstream dump;
	o.dumpToTextStream(dump);
	mrpt::config::CConfigFileMemory c("[map]\n" + dump.str());
	TKeyframeMapOptions b;
	ASSERT_FALSE(b == o);
	b.loadFromConfigFile(c, "map");
#define SAME(f) EXPECT_EQ(b.f, o.f) << #f
	SAME(kf_spacing_m); SAME(kf_spacing_deg); SAME(landmarks_per_keyframe); SAME(selection_grid_cols);
	SAME(selection_grid_rows); SAME(compression_level); SAME(index_cell_m); SAME(draw_landmarks);
	SAME(draw_landmark_max_depth_m); SAME(draw_frame_every_m); SAME(landmark_selection);
	SAME(reobservation_window_m); SAME(reobservation_radius_px); SAME(min_reobservations); SAME(patch_bits);
#undef SAME
	EXPECT_TRUE(b == o);
	std::ostringstream again;
	b.dumpToTextStream(again);
	EXPECT_EQ(again.str(), dump.str());

	// Strict: a key without its unit, a bool with a comment, a bad number, a range.
	auto load = [](const std::string& text) {
		mrpt::config::CConfigFileMemory m(text);
		TKeyframeMapOptions x;
		x.loadFromConfigFile(m, "map");
		return x;
	};
	expectRefused([&] { load("[map]\nkf_spacing = 2\n"); }, {"[map] kf_spacing", "kf_spacing_m"}, "unit");
	EXPECT_TRUE(load("[map]\ndraw_landmarks = true ; draw them\n").draw_landmarks);
	expectRefused([&] { load("[map]\nlandmarks_per_keyframe = 12.5\n"); }, {"[map] landmarks_per_keyframe"}, "integer");
	expectRefused([&] { load("[map]\ncompression_level = 30\n"); }, {"[map] compression_level: must be in [1, 22]"}, "range");
	expectRefused([&] { load("[map]\nlandmark_selection = best\n"); }, {"[map] landmark_selection", "reobserved"}, "choice");
}

TEST(Settings, MapSectionsOfTheVOConfigsAreTheDefaults)
{
	// config/vo.ini and config/vo_sim.ini document the map's defaults in
	// [map]; the survey reads them, and `shadyloc vo` accepts the files.
	for (const char* name : {"vo.ini", "vo_sim.ini"})
	{
		SCOPED_TRACE(name);
		mrpt::config::CConfigFile c(std::string(SHADYLOC_SOURCE_DIR) + "/config/" + name);
		ASSERT_TRUE(c.sectionExists("map"));
		TKeyframeMapOptions o;
		o.loadFromConfigFile(c, "map");
		EXPECT_TRUE(o == TKeyframeMapOptions()) << "the [map] section differs from the defaults";
		EXPECT_NO_THROW(vo::checkVOConfigSections(c));
	}
}
