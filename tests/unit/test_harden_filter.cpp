/* `shadyloc filter` with inputs whose images are stored externally, and
 * pipelines whose filters would write the same derived channel twice. */
#include "../support/TestSupport.h"

#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <fstream>
#include <map>
#include <sstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** n frames whose images are PNG files in imagesDirFor(path). */
void writeExternalRawlog(const std::string& path, int n)
{
	io::RawlogWriter w(path, true);
	for (int i = 0; i < n; i++)
	{
		auto obs = test::syntheticStereoFrame(i, 64, 48);
		w.externalise(obs->imageLeft, "CAMERA_" + std::to_string(i) + "_left.png");
		w.externalise(obs->imageRight, "CAMERA_" + std::to_string(i) + "_right.png");
		w.write(*obs);
	}
	w.commit();
}

/** Counts stereo frames per label, every external image loaded. */
std::map<std::string, int> labelsOf(const std::string& rawlog)
{
	std::map<std::string, int> m;
	for (const auto& s : test::readStereoFrames(rawlog))
	{
		EXPECT_FALSE(s->imageLeft.asCvMatRef().empty()) << rawlog << ": " << s->sensorLabel;
		m[s->sensorLabel]++;
	}
	return m;
}
}  // namespace

TEST(FilterExternalInput, OutputWrittenElsewhereHasAllItsImages)
{
	for (const char* ext : {"", " --external-images"})
	{
		const auto dir = test::tempDir("filter_ext_elsewhere");
		fs::create_directories(dir + "/a");
		fs::create_directories(dir + "/b");
		writeExternalRawlog(dir + "/a/in.rawlog", 3);
		std::string out;
		ASSERT_EQ(test::runCommand(test::appPath() + " filter -q -i " + dir + "/a/in.rawlog -o " + dir + "/b/out.rawlog" + ext, &out), 0)
			<< out;
		// The output stands on its own: the input folder may go away.
		fs::rename(dir + "/a", dir + "/gone");
		std::map<std::string, int> labels;
		try
		{
			labels = labelsOf(dir + "/b/out.rawlog");
		}
		catch (const std::exception& e)
		{
			ADD_FAILURE() << "filter" << ext << ": output not readable on its own: " << e.what();
		}
		EXPECT_EQ(labels["CAMERA"], 3) << ext;
		EXPECT_EQ(labels["CAMERA_mono"], 3) << ext;
		EXPECT_EQ(labels["CAMERA_inv"], 3) << ext;
	}
}

TEST(FilterExternalInput, OutputWithTheInputsStemNeverTouchesItsImages)
{
	for (const char* ext : {"", " --external-images"})
	{
		const auto dir = test::tempDir("filter_ext_stem");
		writeExternalRawlog(dir + "/run.rawlog", 3);
		const auto before = test::snapshot(dir + "/run_Images");
		ASSERT_EQ(before.size(), 7u);  // 3 frames x 2 images, and the folder's output marker
		ASSERT_EQ(before.count(".shadyloc-output"), 1u);
		std::string out;
		const int rc = test::runCommand(
			test::appPath() + " filter -q -i " + dir + "/run.rawlog -o " + dir + "/run.filtered" + ext, &out);
		EXPECT_EQ(test::snapshot(dir + "/run_Images"), before) << "filter" << ext << " changed the input's images: " << out;
		// The input still reads, in colour.
		for (const auto& s : test::readStereoFrames(dir + "/run.rawlog"))
			EXPECT_EQ(s->imageLeft.asCvMatRef().channels(), 3);
		if (rc == 0)
			EXPECT_EQ(labelsOf(dir + "/run.filtered")["CAMERA_inv"], 3) << ext;
		else
			EXPECT_NE(out.find("run_Images"), std::string::npos) << out;
	}
}

TEST(FilterPipelineConfig, TwoFiltersWithOneOutputSuffixNameBothSections)
{
	mrpt::config::CConfigFileMemory cfg(
		"[filters]\npipeline = grey inv\n"
		"[grey]\nclass = CFilterMonochrome\noutput_suffix = _x\n"
		"[inv]\nclass = CFilterInvariant\noutput_suffix = _x\n");
	try
	{
		filters::FilterPipeline::FromConfig(cfg, "dup.ini");
		ADD_FAILURE() << "two filters writing '<sensor>_x' accepted";
	}
	catch (const std::exception& e)
	{
		const std::string w = e.what();
		EXPECT_NE(w.find("[grey]"), std::string::npos) << w;
		EXPECT_NE(w.find("[inv]"), std::string::npos) << w;
		EXPECT_NE(w.find("_x"), std::string::npos) << w;
	}
	// Different sensors: no clash.
	mrpt::config::CConfigFileMemory ok(
		"[filters]\npipeline = a b\n"
		"[a]\nclass = CFilterMonochrome\noutput_suffix = _x\nsensor_labels = LEFTCAM\n"
		"[b]\nclass = CFilterMonochrome\noutput_suffix = _x\nsensor_labels = RIGHTCAM\n");
	EXPECT_NO_THROW(filters::FilterPipeline::FromConfig(ok, "ok.ini"));
}

TEST(FilterPipelineConfig, AppRefusesDuplicateChannels)
{
	const auto dir = test::tempDir("filter_dup");
	test::writeSyntheticRawlog(dir + "/in.rawlog", 2, false);
	{
		std::ofstream f(dir + "/dup.ini");
		f << "[filters]\npipeline = grey inv\n[grey]\nclass = CFilterMonochrome\noutput_suffix = _x\n"
			 "[inv]\nclass = CFilterInvariant\noutput_suffix = _x\n";
	}
	std::string out;
	EXPECT_NE(test::runCommand(test::appPath() + " filter -q -c " + dir + "/dup.ini -i " + dir + "/in.rawlog -o " + dir + "/out.rawlog", &out), 0)
		<< out;
	EXPECT_FALSE(fs::exists(dir + "/out.rawlog"));
	// Filtering a filtered rawlog again would add a second CAMERA_mono stream.
	ASSERT_EQ(test::runCommand(test::appPath() + " filter -q -i " + dir + "/in.rawlog -o " + dir + "/f1.rawlog", &out), 0) << out;
	EXPECT_NE(test::runCommand(test::appPath() + " filter -q -i " + dir + "/f1.rawlog -o " + dir + "/f2.rawlog", &out), 0) << out;
	EXPECT_NE(out.find("CAMERA_mono"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/f2.rawlog"));
}
