/* ShadyLoc tests: paths, shared data, temporary directories, small rawlogs,
 * and the small helpers several test files need.
 *
 * The test sources must also compile as one translation unit (CMake's unity
 * build, CMAKE_UNITY_BUILD), where every file's anonymous namespace is one
 * namespace and a using-directive reaches the files after it: a helper two
 * files need lives here, once; a file's own helper has a name no other test
 * file uses. */
#pragma once

#include <gtest/gtest.h>

#include <shadyloc/geometry/StereoCamera.h>

#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace shadyloc::test
{
/** ../shared/data beside the project, or "" if absent (a fresh clone). */
std::string sharedDataDir();

/** Skips the current test with a clear message if shared data is missing. */
#define SHADYLOC_REQUIRE_SHARED_DATA(sub)                                            \
	do {                                                                             \
		if (shadyloc::test::sharedDataDir().empty() ||                               \
			!std::filesystem::exists(shadyloc::test::sharedDataDir() + "/" + (sub)))   \
			GTEST_SKIP() << "real data '../shared/data/" << (sub)                    \
						 << "' is absent (fresh clone?): test skipped";              \
	} while (0)

/** The default dataset (scripts/make-default-dataset.sh: evening_warm,
 * morning_low_sun, noon, overcast, each .rawlog and .tum): the checkout's
 * rawlogs/generated when complete, else the ctest fixture's rendering
 * (SHADYLOC_FIXTURE_DIR/default_data, FIXTURES default_data), else "". */
std::string defaultDatasetDir();

/** Skips the current test with a clear message if the default dataset is missing. */
#define SHADYLOC_REQUIRE_DEFAULT_DATASET()                                                          \
	do {                                                                                            \
		if (shadyloc::test::defaultDatasetDir().empty())                                            \
			GTEST_SKIP() << "the default dataset is absent (neither rawlogs/generated nor the "       \
							"ctest fixture default_data): make it with scripts/make-default-dataset.sh " \
							"or run the test through ctest; test skipped";                             \
	} while (0)

/** A fresh empty directory for this test (removed at the next call with the same name). */
std::string tempDir(const std::string& name);

/** Runs a shell command, returns its exit status; stdout+stderr into *output. */
int runCommand(const std::string& cmd, std::string* output = nullptr);

std::string appPath();	  //!< the built `shadyloc` executable
/** Starts `shadyloc args...` (appPath) with stdout and stderr to `log`;
 * returns its pid (wait for it with waitpid). */
int spawnApp(const std::vector<std::string>& args, const std::string& log);
/** The whole file as bytes ("" when it cannot be read). */
std::string fileContents(const std::string& path);
/** Writes `contents` as the whole file (binary, replacing it). */
void writeFileContents(const std::string& path, const std::string& contents);
std::string pluginPath();  //!< the built MRPT plugin module
/** SHADYLOC_SOURCE_DIR + "/" + rel: a file of the checkout (config/sim.ini). */
std::string sourcePath(const std::string& rel);

using Bytes = std::vector<uint8_t>;
/** The whole file as bytes (none when it cannot be read). */
Bytes fileBytes(const std::string& path);
/** Writes `b` as the whole file (binary, replacing it). */
void writeBytes(const std::string& path, const Bytes& b);

/** Every regular file under the folder `path` (relative name -> contents);
 * a regular file alone as ".", nothing when `path` does not exist. */
std::map<std::string, std::string> snapshot(const std::string& path);

/** SHADYLOC_UPDATE_GOLDEN is set (and not "0"): tests rewrite their golden
 * files instead of comparing with them. */
bool updatingGolden();

/** The message of the std::exception `f` throws, "" when it throws none. */
std::string errorOf(const std::function<void()>& f);

/** Same size, type and every pixel value. */
bool samePixels(const cv::Mat& a, const cv::Mat& b);

/** A rectified 512x384 stereo camera: fx = fy = 400 px, principal point
 * (256, 192) in both images, baseline 0.12 m. */
geometry::TStereoCalib stereoCalib();

/** Every stereo observation of a rawlog (both styles), external images
 * loaded, read through the project's checked reader. */
std::vector<mrpt::obs::CObservationStereoImages::Ptr> readStereoFrames(const std::string& rawlog);

/** A rectified stereo observation of a grey or colour pair with pinhole
 * calibration c (right camera c.baseline along x), labelled `label`. */
mrpt::obs::CObservationStereoImages stereoObservation(
	const cv::Mat& left, const cv::Mat& right, const geometry::TStereoCalib& c, double timestamp,
	const std::string& label = "CAMERA");

/** A synthetic colour stereo frame: textured, coloured patches, a shadow band
 * (sky-lit: dimmer and bluer) that moves with `frame`. */
mrpt::obs::CObservationStereoImages::Ptr syntheticStereoFrame(int frame, int w = 160, int h = 120);

/** Writes n synthetic frames (w x h) as a rawlog; sensoryFrames selects the
 * action/sensory-frame style instead of bare observations. */
void writeSyntheticRawlog(const std::string& path, int n, bool sensoryFrames, int w = 160, int h = 120);

}  // namespace shadyloc::test
