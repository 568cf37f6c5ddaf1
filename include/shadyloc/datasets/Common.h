/* ShadyLoc — what every dataset importer shares: options, result, errors. */
#pragma once

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/poses/CPose3DQuat.h>

#include <stdexcept>
#include <string>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::datasets
{
/** Bad or inconsistent dataset input; what() names the file / frame at fault. */
class DatasetError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

/** Options common to all importers (section [import] in an .ini file;
 * keys sensor_label, external_images, max_frames, progress_every). */
struct TImportOptions : public mrpt::config::CLoadableOptions
{
	std::string sensorLabel = "CAMERA";	 //!< label of the stereo observations
	bool externalImages = false;  //!< PNG files in <stem>_Images/ instead of inline images
	size_t maxFrames = 0;  //!< import at most this many frames (0: all)
	size_t progressEvery = 100;	 //!< log progress every this many frames (0: never)

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	void validate() const;	//!< throws std::invalid_argument naming the key
};

/** What an import did. */
struct TImportResult
{
	size_t frames = 0;				  //!< stereo observations written
	std::string rawlogPath;			  //!< the rawlog written
	std::string groundTruthPath;	  //!< TUM file written, "" if the dataset has none
	mrpt::img::TCamera leftCamera, rightCamera;	 //!< calibration stored in every frame
	mrpt::poses::CPose3DQuat rightCameraPose;	 //!< right camera in the left camera frame
	double seconds = 0;							 //!< wall time of the import
};

/** Where an importer puts a rawlog's ground truth: "<dir>/<stem>_gt.tum". */
std::string groundTruthPathFor(const std::string& rawlogPath);

}  // namespace shadyloc::datasets
