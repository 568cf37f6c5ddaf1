/* ShadyLoc — KITTI odometry layout (Geiger et al., CVPR 2012) <-> rawlog.
 *
 *   ROOT/sequences/NN/image_2/000000.png ...  left colour camera (cam2)
 *   ROOT/sequences/NN/image_3/000000.png ...  right colour camera (cam3)
 *   ROOT/sequences/NN/calib.txt   "P0: 12 numbers" ... "P3: ..." (3x4, row-major)
 *   ROOT/sequences/NN/times.txt   one timestamp [s] per frame
 *   ROOT/poses/NN.txt             optional: 3x4 row-major T_world_cam0 per frame
 *
 * Rectified projection matrices are P_i = K_i [I | t_i]: t_i = K_i^-1 P_i[:,3]
 * is the translation from the reference camera (cam0) frame to camera i, so
 * camera i sits at -t_i in cam0's frame. See docs/datasets.md.
 */
#pragma once

#include <shadyloc/datasets/Common.h>

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/system/COutputLogger.h>

#include <array>
#include <map>
#include <string>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::datasets
{
using TMatrix34 = mrpt::math::CMatrixFixed<double, 3, 4>;

/** A KITTI calib.txt: every "Name: 12 numbers" line (P0..P3, Tr, ...). */
struct TKittiCalib
{
	std::map<std::string, TMatrix34> P;	 //!< by name: "P0", "P2", "Tr", ...

	/** Reads the file; throws DatasetError naming file and line on a bad line. */
	static TKittiCalib FromFile(const std::string& path);
	/** P[name], or DatasetError naming `path` if missing. */
	const TMatrix34& get(const std::string& name, const std::string& path) const;
};

/** Intrinsics of a rectified projection matrix P = K [I|t] (zero distortion). */
mrpt::img::TCamera cameraFromProjection(const TMatrix34& P, uint32_t ncols, uint32_t nrows);
/** t = K^-1 P[:,3]: translation from the reference frame to this camera [m]. */
mrpt::math::TPoint3D translationFromProjection(const TMatrix34& P);
/** P = K [I | t] for a camera and a translation t [m]. */
TMatrix34 projectionFromCamera(const mrpt::img::TCamera& cam, const mrpt::math::TPoint3D& t);

/** "ROOT/sequences/NN". */
std::string kittiSequenceDir(const std::string& root, const std::string& sequence);

/** Imports one KITTI odometry sequence (colour cameras 2 and 3).
 *
 * Stereo geometry: left = cam2, right = cam3, rightCameraPose = (b,0,0) with
 * b = t2.x - t3.x (the images are rectified to a pure-x baseline; the mm-size
 * y/z terms of KITTI's P matrices are dropped from the pair). Ground truth
 * (poses/NN.txt, if present) is converted from KITTI's cam0 to our left camera:
 * T_world_left = T_world_cam0 * T_cam0_cam2, T_cam0_cam2 = translation(-t2);
 * world = KITTI's world (cam0 at frame 0). Written beside the rawlog as TUM
 * (groundTruthPathFor), timestamps equal to the rawlog's (times.txt seconds
 * taken as seconds after the Unix epoch). */
class KittiImporter : public mrpt::system::COutputLogger
{
   public:
	KittiImporter();
	TImportOptions options;

	/** Throws DatasetError naming the file/frame at fault; then no rawlog,
	 * temporary file or ground truth is left behind. */
	TImportResult run(const std::string& root, const std::string& sequence, const std::string& outRawlog);
};

/** Exports the stereo observations of one sensor label to a KITTI layout.
 *
 * Writes sequences/NN/image_2, image_3 (PNG, "%06d.png"), calib.txt (P0 = P2
 * = K_left [I|0], P1 = P3 = K_right [I | (-b,0,0)]: the left camera is the
 * reference camera), times.txt, and poses/NN.txt (T_world_left per frame, KITTI
 * 3x4) from a TUM file when given. The sequence directory is staged and renamed
 * into place at the end, so a failure leaves no half-written sequence. */
class KittiExporter : public mrpt::system::COutputLogger
{
   public:
	KittiExporter();
	struct TOptions : public mrpt::config::CLoadableOptions
	{
		std::string sequence = "00";		 //!< NN
		std::string sensorLabel = "CAMERA";	 //!< which stereo observations to export
		std::string groundTruthTum;	 //!< TUM file for poses/NN.txt ("" = none)
		double gtTimeTolerance = 1e-3;	//!< max |t_frame - t_gt| to pair a pose [s]
		bool absoluteTimes = false;	 //!< times.txt: absolute [s] instead of since frame 0
		size_t progressEvery = 100;	 //!< log progress every this many frames (0: never)

		void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
		void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
		void dumpToTextStream(std::ostream& out) const override;
		void validate() const;	//!< throws std::invalid_argument naming the key
	};
	TOptions options;

	struct TResult
	{
		size_t frames = 0;	//!< stereo frames written
		bool poses = false;	 //!< poses/NN.txt written
		double seconds = 0;
	};
	TResult run(const std::string& inRawlog, const std::string& outRoot);
};

}  // namespace shadyloc::datasets
