/* ShadyLoc tests: rendered stereo sequences shared between test processes.
 *
 * ctest runs every test in its own process; a sequence several tests need is
 * rendered once by a ctest fixture (FIXTURES_SETUP in tests/CMakeLists.txt)
 * into the build tree, and the tests that require the fixture read it
 * (ctest sets SHADYLOC_FIXTURE_DIR for them). Run outside ctest (the test
 * binary directly), the same functions render in-process instead, once per
 * process; the frames are the same bytes either way. */
#pragma once

#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/sim/SimOptions.h>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace shadyloc::test
{
/** Rectified colour stereo frames (CV_8UC3, BGR) with their calibration. */
struct TStereoSequence
{
	geometry::TStereoCalib calib;
	std::vector<cv::Mat> left, right;
	std::vector<double> t;	//!< timestamps [s]
	std::vector<Eigen::Isometry3d> T_world_left;  //!< ground truth: left camera in the world
};

/** A pose in the synthetic corridor: `z` metres in, `x` to the side, 0.1 m
 * up, turned `yawDeg` about the vertical (y) axis. */
Eigen::Isometry3d corridorPose(double z, double x, double yawDeg = 0);

/** The shipped simulator config (config/sim.ini), its camera shrunk to w x h
 * for speed. */
sim::TSimOptions smallSimOptions(int w = 160, int h = 120);

/** SHADYLOC_FIXTURE_DIR, or "" outside ctest. */
std::string fixtureDir();

/** The synthetic corridor (sim::SyntheticCorridor, default options) along
 * examplePose(k, speed), k < frames, pixel noise seeded by k. t[k] = 0.1 k. */
const TStereoSequence& corridorSequence(int frames, double speed);
/** Writes the corridor sequences the fixture provides into `dir` (the
 * fixture's setup test, TestFixtures.WriteCorridorSequences). */
void writeCorridorFixtures(const std::string& dir);

/** The first 30 frames of a traversal of config/sim.ini (512x384) as
 * `shadyloc sim --frames 30` renders them; the ctest fixture renders noon and
 * overcast. Ground truth from the TUM file (9 decimals). */
const TStereoSequence& simSequence(const std::string& traversal);
/** The folder holding <traversal>.rawlog and .tum of simSequence (the
 * fixture's, or rendered once per process outside ctest). */
std::string simSequenceDir(const std::string& traversal);
constexpr int kSimFixtureFrames = 30;

}  // namespace shadyloc::test
