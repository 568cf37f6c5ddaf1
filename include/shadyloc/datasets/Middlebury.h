/* ShadyLoc — Middlebury 2014 stereo scene (Scharstein et al., GCPR 2014) -> rawlog.
 *
 * SCENE/im0.png (left), im1.png (right), calib.txt:
 *   cam0=[f 0 cx0; 0 f cy; 0 0 1]  cam1=[f 0 cx1; 0 f cy; 0 0 1]
 *   doffs=cx1-cx0 [px]  baseline=[mm]  width=  height=  ndisp= ...
 */
#pragma once

#include <shadyloc/datasets/Common.h>

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/system/COutputLogger.h>

#include <string>

namespace shadyloc::datasets
{
/** The parts of a Middlebury calib.txt we use (all kept exactly as written). */
struct TMiddleburyCalib
{
	mrpt::math::CMatrixDouble33 cam0, cam1;	//!< intrinsics of im0 / im1 [px]
	double doffs = 0;						 //!< x-difference of principal points [px]
	double baseline_mm = 0;					 //!< camera baseline [mm]
	uint32_t width = 0, height = 0;			 //!< image size [px]
	int ndisp = 0;							 //!< disparity range bound [px] (0 if absent)

	/** Parses "key=value" lines (spaces anywhere); throws DatasetError naming
	 * the file and the missing/bad key. */
	static TMiddleburyCalib FromFile(const std::string& path);
};

/** One Middlebury scene -> a rawlog with one stereo frame: leftCamera from cam0,
 * rightCamera from cam1 (its own cx), rightCameraPose = (baseline/1000, 0, 0). */
class MiddleburyImporter : public mrpt::system::COutputLogger
{
   public:
	MiddleburyImporter();
	TImportOptions options;
	std::string leftImage = "im0.png";	//!< file name inside the scene folder
	std::string rightImage = "im1.png";	 //!< e.g. "im1E.png" / "im1L.png" for lighting variants
	double timestamp = 0;  //!< timestamp of the frame [s since Unix epoch]

	TImportResult run(const std::string& sceneDir, const std::string& outRawlog);
};

}  // namespace shadyloc::datasets
