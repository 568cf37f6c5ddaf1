/* ShadyLoc — Oxford RobotCar traversal (Maddern et al., IJRR 2017) -> rawlog.
 *
 *   TRAVERSAL/stereo.timestamps       "<t_us> <chunk>" per frame (Unix time, microseconds)
 *   TRAVERSAL/stereo/left/<t_us>.png  raw Bayer GBRG mosaic, 8-bit (Bumblebee XB3 wide pair)
 *   TRAVERSAL/stereo/right/<t_us>.png
 *   TRAVERSAL/gps/ins.csv             INS poses: header line, then one row per pose
 *   TRAVERSAL/vo/vo.csv               the dataset's VO (not read: see docs/datasets.md)
 *   MODELS/stereo_wide_left.txt, stereo_wide_right.txt           (the SDK's models/)
 *   MODELS/stereo_wide_left_distortion_lut.bin, ..._right_...
 *   EXTRINSICS/stereo.txt, ins.txt    (the SDK's extrinsics/, for the ground truth)
 *
 * Images are demosaiced (bilinear, as the SDK does) and remapped through the
 * SDK's look-up tables, which undistort and rectify the pair in one step; the
 * model files then give the rectified intrinsics and the lens offsets. See
 * docs/datasets.md for the frames and why.
 */
#pragma once

#include <shadyloc/datasets/Common.h>

#include <mrpt/system/COutputLogger.h>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace shadyloc::datasets
{
/** How the raw mosaic becomes colour: bilinear (the SDK's), OpenCV's
 * edge-aware interpolation, or half resolution (one BGR pixel per 2x2 Bayer
 * cell, green averaged: no interpolated colour at all). */
enum class TDemosaic
{
	Bilinear,
	EdgeAware,
	HalfResolution
};

/** One camera model of the SDK's models folder.
 *   <name>.txt: "fx fy cx cy" [px], then 4 lines of the 4x4 G_camera_image
 *     (the lens's image frame, z forward, into the camera's base frame,
 *     x forward; for the stereo camera it holds the offset to the lens).
 *   <name>_distortion_lut.bin: 2 w h float64 values, all u then all v, one
 *     (u, v) per rectified pixel in row-major order, 0-based: where in the
 *     raw image that pixel is sampled (bilinear). */
struct TRobotCarCameraModel
{
	std::string name;  //!< e.g. "stereo_wide_left"
	double fx = 0, fy = 0, cx = 0, cy = 0;	//!< rectified intrinsics [px]
	Eigen::Isometry3d G_camera_image = Eigen::Isometry3d::Identity();
	cv::Mat mapX, mapY;	 //!< CV_32FC1 look-up table for cv::remap (empty until readLut)

	/** Reads MODELS/<name>.txt; DatasetError naming the file and line. */
	static TRobotCarCameraModel FromFile(const std::string& modelsDir, const std::string& name);
	/** Reads MODELS/<name>_distortion_lut.bin for w x h images; the file
	 * must hold exactly 2 w h finite doubles (DatasetError otherwise). */
	void readLut(const std::string& modelsDir, int width, int height);
	/** The same camera at half resolution (TDemosaic::HalfResolution): a
	 * half-resolution pixel x covers full-resolution 2x .. 2x+1, centre
	 * 2x + 0.5, so fx/2, fy/2, (cx - 0.5)/2, (cy - 0.5)/2; the table is
	 * averaged over each 2x2 block and mapped the same way. Needs the table
	 * read, of even width and height. */
	TRobotCarCameraModel halved() const;
	/** A raw GBRG mosaic (8-bit, 1 channel) -> demosaiced, rectified BGR
	 * (HalfResolution: on a halved() model, the raw image twice its size). */
	cv::Mat rectify(const cv::Mat& raw, const std::string& what, TDemosaic method = TDemosaic::Bilinear) const;
};

/** The SDK's "x y z roll pitch yaw" [m, rad] as a transform, R = Rz Ry Rx. */
Eigen::Isometry3d robotcarTransform(const double xyzrpy[6]);
/** One line "x y z roll pitch yaw" of an SDK extrinsics file. */
Eigen::Isometry3d readRobotCarExtrinsics(const std::string& path);

/** One row of gps/ins.csv: T_world_ins from northing, easting, down, roll,
 * pitch, yaw (world: UTM north-east-down; the INS frame x forward, z down). */
struct TRobotCarInsPose
{
	int64_t t_us = 0;
	Eigen::Isometry3d T_world_ins = Eigen::Isometry3d::Identity();
};
/** Reads ins.csv (columns found by name in the header); every row must have
 * the header's field count, times must increase: DatasetError naming file:line. */
std::vector<TRobotCarInsPose> readRobotCarIns(const std::string& path);
/** Pose at t_us: positions linear, rotations slerp between the two rows
 * around it. DatasetError (starting with `where`) if t_us is outside the rows. */
Eigen::Isometry3d interpolateRobotCarIns(
	const std::vector<TRobotCarInsPose>& ins, int64_t t_us, const std::string& where);

/** Imports the wide-baseline pair (stereo/left, stereo/right) of a traversal.
 *
 * Ground truth (gps/ins.csv, if groundTruth): the left lens's image frame
 * (x right, y down, z forward) in the INS's world,
 *   T_world_left(t) = T_world_ins(t) * (G_stereo_vehicle * G_vehicle_ins)^-1 * G_camera_image(left)
 * with G_stereo_vehicle from EXTRINSICS/stereo.txt and G_vehicle_ins from
 * EXTRINSICS/ins.txt, composed as the SDK's project_laser_into_camera does.
 * World = UTM north, east, down (absolute: traversals share it), shifted
 * by -groundTruthOrigin. */
class RobotCarImporter : public mrpt::system::COutputLogger
{
   public:
	RobotCarImporter();
	TImportOptions options;	 //!< maxFrames counts frames written
	std::string modelsDir;	//!< the SDK's models folder (required)
	std::string extrinsicsDir;	//!< the SDK's extrinsics folder (required with groundTruth)
	bool groundTruth = true;  //!< write <stem>_gt.tum from gps/ins.csv
	/** Subtracted from every ground-truth position (UTM northing, easting,
	 * down [m]): float consumers (OpenGL rendering) lose half a metre at
	 * 5.7e6 m; give every traversal of a route the same origin. */
	Eigen::Vector3d groundTruthOrigin = Eigen::Vector3d::Zero();
	size_t firstFrame = 0;	//!< first line of stereo.timestamps imported (0-based)
	size_t stride = 1;	//!< import every stride-th frame from firstFrame
	cv::Rect crop;	//!< of the rectified images (empty: none); intrinsics follow
	/** The SDK's bilinear by default; the others leave fewer or no colour
	 * fringes, which the invariant channel is sensitive to (docs). */
	TDemosaic demosaic = TDemosaic::Bilinear;

	/** DatasetError naming the file / frame at fault; then nothing is written. */
	TImportResult run(const std::string& traversalDir, const std::string& outRawlog);
};

}  // namespace shadyloc::datasets
