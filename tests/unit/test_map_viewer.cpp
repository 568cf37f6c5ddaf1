/* A map file in MRPT's RawLogViewer (issue #25): tests/tools/viewer_probe
 * takes the viewer's path (plugins loaded as `-l` does, the file read into a
 * CRawlog with any class allowed, the selected entry's text and 3D objects)
 * without a display. docs/map.md, "In RawLogViewer". */
#include <shadyloc/map/CKeyframeMap.h>

#include "../support/TestSupport.h"
#include "test_map_support.h"

#include <regex>

using namespace shadyloc;

namespace
{
std::string probe(const std::string& args, int* rc)
{
	std::string out;
	*rc = test::runCommand(std::string(SHADYLOC_VIEWER_PROBE) + " " + args, &out);
	return out;
}
}  // namespace

TEST(MapInViewer, ThePluginShowsTheMapsSummaryAndDrawing)
{
	const std::string dir = test::tempDir("map_viewer");
	for (const bool landmarks : {false, true})
	{
		SCOPED_TRACE(landmarks ? "draw_landmarks" : "no landmarks");
		auto m = test::makeSyntheticMap();
		m->options.draw_landmarks = landmarks;  // stored with the map: the viewer sees it
		const std::string path = dir + (landmarks ? "/lm.kfmap" : "/m.kfmap");
		m->saveToFile(path);
		// The text the viewer shows is the loaded map's summary, whole.
		const std::string summary = CKeyframeMap::LoadFromFile(path)->asString();
		int rc = 0;
		const std::string out = probe("-l " + test::pluginPath() + " " + path, &rc);
		ASSERT_EQ(rc, 0) << out;
		EXPECT_NE(out.find("entries: 1\n[0] etOther shadyloc::CKeyframeMap\n"), std::string::npos) << out;
		EXPECT_NE(out.find(summary), std::string::npos) << "summary:\n" << summary << "\nprobe:\n" << out;
		EXPECT_NE(summary.find("24 keyframes"), std::string::npos) << summary;
		// Path and chevrons; with draw_landmarks a point cloud per channel too.
		const std::string expected = landmarks ? "drawing: 4 objects (mrpt::opengl::CSetOfTriangles, "
												 "mrpt::opengl::CSetOfTriangles, mrpt::opengl::CPointCloudColoured, "
												 "mrpt::opengl::CPointCloudColoured)"
											   : "drawing: 2 objects (mrpt::opengl::CSetOfTriangles, "
												 "mrpt::opengl::CSetOfTriangles)";
		EXPECT_NE(out.find(expected), std::string::npos) << out;
		// The summary says the same of the landmarks.
		EXPECT_EQ(summary.find("landmarks not drawn (draw_landmarks off)") != std::string::npos, !landmarks) << summary;
		EXPECT_EQ(std::regex_search(summary, std::regex("[1-9][0-9]* landmarks within 30 m")), landmarks) << summary;
	}
}

TEST(MapInViewer, WithoutThePluginNothingLoads)
{
	const std::string path = test::tempDir("map_viewer_bare") + "/m.kfmap";
	test::makeSyntheticMap()->saveToFile(path);
	// MRPT reads the file, stops at the unknown class with its error, and
	// reports success with no entry (RawLogViewer: "Zero entries loaded").
	int rc = 0;
	const std::string out = probe(path, &rc);
	EXPECT_EQ(rc, 0) << out;
	EXPECT_NE(out.find("entries: 0\n"), std::string::npos) << out;
	EXPECT_NE(out.find("'shadyloc::CKeyframeMap' which is not registered"), std::string::npos) << out;
	EXPECT_EQ(out.find("[0]"), std::string::npos) << out;
}

TEST(MapInViewer, MapInfoPrintsTheDrawingLine)
{
	const std::string path = test::tempDir("map_viewer_info") + "/m.kfmap";
	const auto m = test::makeSyntheticMap();
	m->saveToFile(path);
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " map-info " + path, &out), 0) << out;
	const std::string line = m->drawingSummary();
	EXPECT_NE(line.find("the keyframe chain of 24 keyframes"), std::string::npos) << line;
	EXPECT_NE(out.find("\n  " + line + "\n"), std::string::npos) << "line:\n" << line << "\nmap-info:\n" << out;
}
