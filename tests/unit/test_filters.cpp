/* Observation filters and the streaming rawlog processor: round trips through
 * the app, stock MRPT tools with and without the plugin, and bad input. */
#include "../support/TestSupport.h"

#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>

#include <fstream>
#include <regex>

using namespace shadyloc;
using namespace shadyloc::test;
namespace fs = std::filesystem;

namespace
{
std::string q(const std::string& s) { return "'" + s + "'"; }

// Every observation of a rawlog, in order, through our checked reader.
std::vector<mrpt::obs::CObservation::Ptr> readAll(const std::string& path, size_t* objects = nullptr)
{
	io::RawlogReader r(path);
	std::vector<mrpt::obs::CObservation::Ptr> all;
	size_t n = 0;
	while (auto o = r.next())
	{
		n++;
		for (auto& ob : io::observationsIn(o)) all.push_back(ob);
	}
	if (objects) *objects = n;
	return all;
}

bool haveRawlogEdit() { return runCommand("command -v rawlog-edit") == 0; }

// "Overall number of objects : N" from `rawlog-edit --info`, or -1.
int rawlogEditCount(const std::string& rawlog, const std::string& plugin, int* exitCode)
{
	std::string out;
	const std::string p = plugin.empty() ? "" : " -p " + q(plugin);
	*exitCode = runCommand("rawlog-edit" + p + " -i " + q(rawlog) + " --info", &out);
	std::smatch m;
	if (std::regex_search(out, m, std::regex("Overall number of objects\\s*:\\s*(\\d+)")))
		return std::stoi(m[1]);
	return -1;
}

// Is there any file in dir whose name starts with "." + stem (our temporaries) or equals name?
bool leftovers(const std::string& dir, const std::string& name)
{
	for (auto& e : fs::directory_iterator(dir))
	{
		const auto f = e.path().filename().string();
		if (f == name || f.rfind("." + name, 0) == 0 || f.rfind(fs::path(name).stem().string() + "_Images", 0) == 0)
			return true;
	}
	return false;
}
}  // namespace

class FilterRoundTrip : public ::testing::TestWithParam<bool>
{
};

// Must-show 5: every input object is kept, each camera frame gains its mono and
// invariant channels, pixels and calibration are right, and the record of the
// options reads back into the same pipeline.
TEST_P(FilterRoundTrip, AppKeepsEverythingAndAddsChannels)
{
	const bool sf = GetParam();
	const auto dir = tempDir(std::string("filter_rt_") + (sf ? "sf" : "obs"));
	const auto in = dir + "/in.rawlog", out = dir + "/out.rawlog";
	const int N = 6;
	writeSyntheticRawlog(in, N, sf);
	std::string log;
	ASSERT_EQ(
		runCommand(appPath() + " filter -i " + in + " -o " + out + " -c " SHADYLOC_SOURCE_DIR "/config/filters.ini", &log),
		0)
		<< log;

	size_t nIn = 0, nOut = 0;
	const auto obsIn = readAll(in, &nIn);
	const auto obsOut = readAll(out, &nOut);
	EXPECT_EQ(nOut, sf ? nIn : nIn * 3 + 1) << "objects out";  // +1: the record
	ASSERT_EQ(obsOut.size(), obsIn.size() * 3 + 1);

	auto record = std::dynamic_pointer_cast<mrpt::obs::CObservationComment>(obsOut[0]);
	ASSERT_TRUE(record);
	const auto recText = filters::readPipelineRecord(out);
	ASSERT_FALSE(recText.empty());
	mrpt::config::CConfigFileMemory recCfg(recText);
	const auto again = filters::FilterPipeline::FromConfig(recCfg, "record");
	EXPECT_EQ(again.asIni(), filters::FilterPipeline::FromConfigFile(SHADYLOC_SOURCE_DIR "/config/filters.ini").asIni());

	const image::InvariantTransform inv(image::InvariantParams::FromAlphaBeta(0.48, 0.5065));
	for (int i = 0; i < N; i++)
	{
		auto src = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(obsOut[1 + 3 * i]);
		auto mono = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(obsOut[2 + 3 * i]);
		auto invo = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(obsOut[3 + 3 * i]);
		ASSERT_TRUE(src && mono && invo);
		EXPECT_EQ(src->sensorLabel, "CAMERA");
		EXPECT_EQ(mono->sensorLabel, "CAMERA_mono");
		EXPECT_EQ(invo->sensorLabel, "CAMERA_inv");
		EXPECT_EQ(mono->timestamp, src->timestamp);
		EXPECT_EQ(invo->timestamp, src->timestamp);
		EXPECT_EQ(invo->leftCamera.intrinsicParams, src->leftCamera.intrinsicParams);
		EXPECT_EQ(invo->rightCameraPose, src->rightCameraPose);
		ASSERT_TRUE(invo->hasImageRight);
		EXPECT_FALSE(invo->imageLeft.isColor());

		cv::Mat expectMono, expectInvL, expectInvR;
		image::toMonochrome(src->imageLeft.asCvMatRef(), expectMono, image::ChannelOrder::BGR);
		inv.applyPair(src->imageLeft.asCvMatRef(), src->imageRight.asCvMatRef(), expectInvL, expectInvR);
		EXPECT_EQ(cv::norm(expectMono, mono->imageLeft.asCvMatRef(), cv::NORM_INF), 0);
		EXPECT_EQ(cv::norm(expectInvL, invo->imageLeft.asCvMatRef(), cv::NORM_INF), 0);
		EXPECT_EQ(cv::norm(expectInvR, invo->imageRight.asCvMatRef(), cv::NORM_INF), 0);
	}
	EXPECT_FALSE(leftovers(dir, ".out.rawlog.tmp")) << "temporary file left behind";
}

INSTANTIATE_TEST_SUITE_P(
	BothRawlogStyles, FilterRoundTrip, ::testing::Values(false, true),
	[](const auto& info) { return info.param ? "SensoryFrames" : "Observations"; });

// Must-show 5, stock tools: rawlog-edit counts every object of the output
// with and without our plugin (it holds only stock classes).
TEST(FilterStockTools, RawlogEditCountsAllWithAndWithoutPlugin)
{
	if (!haveRawlogEdit()) GTEST_SKIP() << "rawlog-edit not installed (scripts/setup.sh installs mrpt-apps)";
	const auto dir = tempDir("filter_stock");
	const auto in = dir + "/in.rawlog", out = dir + "/out.rawlog";
	writeSyntheticRawlog(in, 4, false);
	ASSERT_EQ(runCommand(appPath() + " filter -q -i " + in + " -o " + out), 0);
	int rc = 0;
	EXPECT_EQ(rawlogEditCount(out, "", &rc), 4 * 3 + 1);
	EXPECT_EQ(rc, 0);
	EXPECT_EQ(rawlogEditCount(out, pluginPath(), &rc), 4 * 3 + 1);
	EXPECT_EQ(rc, 0);
}

// The plugin registers our classes in stock tools: a rawlog holding one of
// them is read whole with it, and (MRPT's behaviour we guard against) silently
// cut short without it.
TEST(FilterStockTools, PluginMakesOurClassesReadable)
{
	if (!haveRawlogEdit()) GTEST_SKIP() << "rawlog-edit not installed (scripts/setup.sh installs mrpt-apps)";
	const auto dir = tempDir("filter_plugin");
	const auto path = dir + "/ours.rawlog";
	{
		mrpt::io::CFileGZOutputStream f(path);
		auto a = mrpt::serialization::archiveFrom(f);
		a << *syntheticStereoFrame(0) << *CFilterInvariant::Create() << *syntheticStereoFrame(1);
	}
	int rc = 0;
	EXPECT_EQ(rawlogEditCount(path, pluginPath(), &rc), 3) << "with the plugin every object is read";
	EXPECT_EQ(rc, 0);
	EXPECT_LT(rawlogEditCount(path, "", &rc), 3) << "without it MRPT stops at our class";
	size_t n = 0;
	readAll(path, &n);	// our reader, with our classes registered in-process
	EXPECT_EQ(n, 3u);
}

TEST(FilterExternalImages, WritesPngsAndReadsBack)
{
	const auto dir = tempDir("filter_ext");
	const auto in = dir + "/in.rawlog", out = dir + "/out.rawlog";
	writeSyntheticRawlog(in, 3, false);
	std::string log;
	ASSERT_EQ(runCommand(appPath() + " filter -q --external-images -i " + in + " -o " + out, &log), 0) << log;
	ASSERT_TRUE(fs::is_directory(dir + "/out_Images"));
	size_t pngs = 0;
	for (auto& e : fs::directory_iterator(dir + "/out_Images")) pngs += e.path().extension() == ".png";
	EXPECT_EQ(pngs, 3u * 2 * 2);  // frames x channels x eyes
	const auto all = readAll(out);
	auto invo = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(all[3]);
	ASSERT_TRUE(invo);
	EXPECT_TRUE(invo->imageLeft.isExternallyStored());
	io::loadExternalImages(*invo);
	EXPECT_EQ(invo->imageLeft.getWidth(), 160u);
}

TEST(FilterClasses, SerialisationRoundTrip)
{
	auto f = CFilterInvariant::Create();
	auto p = image::InvariantParams::FromWavelengths(450, 550, 650);
	p.linearisation = image::Linearisation::Gamma;
	p.gamma = 1.8;
	f->setParams(p);
	f->common.sensor_labels = "LEFT_CAM";
	mrpt::io::CMemoryStream buf;
	auto a = mrpt::serialization::archiveFrom(buf);
	a << *f << *CFilterMonochrome::Create() << *CFilterLinearise::Create();
	buf.Seek(0);
	auto back = a.ReadObject<CFilterInvariant>();
	ASSERT_TRUE(back);
	EXPECT_EQ(back->optionsAsIni(), f->optionsAsIni());
	EXPECT_TRUE(a.ReadObject<CFilterMonochrome>());
	EXPECT_TRUE(a.ReadObject<CFilterLinearise>());
	// The deserialised filter works (its tables were rebuilt).
	cv::Mat img(8, 8, CV_8UC3, cv::Scalar(30, 90, 200)), o1, o2;
	back->transformImage(img, o1);
	f->transformImage(img, o2);
	EXPECT_EQ(cv::norm(o1, o2, cv::NORM_INF), 0);
}

TEST(FilterConfig, BadOptionsNameSectionAndKey)
{
	auto load = [](const std::string& ini) {
		mrpt::config::CConfigFileMemory c(ini);
		return filters::FilterPipeline::FromConfig(c, "test.ini");
	};
	auto expectError = [&](const std::string& ini, const std::string& mustContain) {
		try
		{
			load(ini);
			ADD_FAILURE() << "no error for:\n" << ini;
		}
		catch (const std::exception& e)
		{
			EXPECT_NE(std::string(e.what()).find(mustContain), std::string::npos)
				<< "message '" << e.what() << "' lacks '" << mustContain << "'";
		}
	};
	expectError("[filters]\n", "pipeline");
	expectError("[filters]\npipeline = a\n[a]\nclass = CNoSuchFilter\n", "CNoSuchFilter");
	expectError("[filters]\npipeline = a\n[a]\nclass = CFilterInvariant\nalpha = 7\n", "alpha");
	expectError("[filters]\npipeline = a\n[a]\nclass = CFilterInvariant\nlinearisation = log\n", "[a]");
	expectError(
		"[filters]\npipeline = a\n[a]\nclass = CFilterInvariant\nalpha=0.4\npeak_wavelength_blue_nm=450\n",
		"not both");
	const auto p = load(
		"[filters]\npipeline = a\n[a]\nclass = CFilterInvariant\npeak_wavelength_blue_nm=470\n"
		"peak_wavelength_green_nm=540\npeak_wavelength_red_nm=620\n");
	auto inv = std::dynamic_pointer_cast<CFilterInvariant>(p.filters.at(0));
	ASSERT_TRUE(inv);
	EXPECT_NEAR(inv->params().alpha + inv->params().beta, 1.0, 1e-12);
}

// ---- Must-show 6: bad input gives a clear error and no output ----------------
// Not in an anonymous namespace: the parameterised suite derives from it.
struct BadCase
{
	std::string name;
	std::function<void(const std::string& dir, const std::string& in)> make;
	std::string expectInMessage;
};
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

namespace
{
void writePlain(const std::string& path, const std::vector<const mrpt::serialization::CSerializable*>& objs)
{
	mrpt::io::CFileOutputStream f(path);
	auto a = mrpt::serialization::archiveFrom(f);
	for (auto* o : objs) a << *o;
}
}  // namespace

class FilterBadInput : public ::testing::TestWithParam<BadCase>
{
};

TEST_P(FilterBadInput, ClearErrorNonZeroExitNoOutput)
{
	const auto& c = GetParam();
	const auto dir = tempDir("filter_bad_" + c.name);
	const auto in = dir + "/in.rawlog", out = dir + "/out.rawlog";
	c.make(dir, in);
	std::string log;
	const int rc = runCommand(appPath() + " filter -q -i " + in + " -o " + out, &log);
	EXPECT_NE(rc, 0) << log;
	std::cout << "    " << c.name << ": " << log;
	EXPECT_NE(log.find(c.expectInMessage), std::string::npos)
		<< "message should contain '" << c.expectInMessage << "':\n" << log;
	EXPECT_FALSE(fs::exists(out)) << "output written despite the error";
	EXPECT_FALSE(fs::exists(dir + "/.out.rawlog.tmp")) << "temporary file left behind";
	EXPECT_FALSE(fs::exists(dir + "/out_Images")) << "images directory left behind";
}

INSTANTIATE_TEST_SUITE_P(
	Cases, FilterBadInput,
	::testing::Values(
		BadCase{"missing", [](auto&, auto&) {}, "no such rawlog file"},
		BadCase{
			"unknown_class",
			[](auto&, const std::string& in) {
				// A registered class written, then its stored name altered (same
				// length): the reader meets a class nobody registered.
				auto a = syntheticStereoFrame(0), b = syntheticStereoFrame(1);
				auto f = CFilterLinearise::Create();
				writePlain(in, {a.get(), f.get(), b.get()});
				auto bytes = fileContents(in);
				const std::string from = "shadyloc::CFilterLinearise", to = "shadyloc::CFilterXinearise";
				bytes.replace(bytes.find(from), from.size(), to);
				writeFileContents(in, bytes);
			},
			"object #1: Stored object has class 'shadyloc::CFilterXinearise'"},
		BadCase{
			"truncated",
			[](auto&, const std::string& in) {
				auto a = syntheticStereoFrame(0), b = syntheticStereoFrame(1);
				writePlain(in, {a.get(), b.get()});
				auto bytes = fileContents(in);
				writeFileContents(in, bytes.substr(0, bytes.size() * 3 / 4));
			},
			"object #1"},
		BadCase{
			"truncated_gz",
			[](auto&, const std::string& in) {
				writeSyntheticRawlog(in, 3, false);
				auto bytes = fileContents(in);
				writeFileContents(in, bytes.substr(0, bytes.size() / 2));
			},
			"object #1"},
		BadCase{
			"corrupt",
			[](auto&, const std::string& in) {
				auto a = syntheticStereoFrame(0);
				writePlain(in, {a.get()});
				writeFileContents(in, fileContents(in) + std::string("\x7f garbage after the last object", 32));
			},
			"object #1"},
		BadCase{
			"empty",
			[](auto&, const std::string& in) { writeFileContents(in, ""); },
			"holds no objects"},
		BadCase{
			"missing_external_image",
			[](const std::string& dir, const std::string& in) {
				fs::create_directories(dir + "/in_Images");
				auto a = syntheticStereoFrame(0), b = syntheticStereoFrame(1);
				for (auto* o : {a.get(), b.get()})
				{
					const std::string stem = "f" + std::to_string(o == a.get() ? 0 : 1);
					o->imageLeft.saveToFile(dir + "/in_Images/" + stem + "_L.png");
					o->imageRight.saveToFile(dir + "/in_Images/" + stem + "_R.png");
					o->imageLeft.setExternalStorage(stem + "_L.png");
					o->imageRight.setExternalStorage(stem + "_R.png");
				}
				writePlain(in, {a.get(), b.get()});
				fs::remove(dir + "/in_Images/f1_R.png");
			},
			"object #1: "},
		BadCase{
			"grey_image",
			[](auto&, const std::string& in) {
				auto a = syntheticStereoFrame(0), b = syntheticStereoFrame(1);
				b->imageLeft = b->imageLeft.grayscale();
				b->imageRight = b->imageRight.grayscale();
				writePlain(in, {a.get(), b.get()});
			},
			"object #1: shadyloc::CFilterInvariant: sensor 'CAMERA'"}),
	[](const auto& info) { return info.param.name; });
