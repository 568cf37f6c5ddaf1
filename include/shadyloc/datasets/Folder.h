/* ShadyLoc — a folder of left images, a folder of right images and a
 * calibration .ini -> rawlog. Pairs by sorted file name (n-th left with n-th
 * right). Example calibration: config/folder_calib_example.ini. */
#pragma once

#include <shadyloc/core/Options.h>
#include <shadyloc/datasets/Common.h>

#include <mrpt/img/TCamera.h>
#include <mrpt/system/COutputLogger.h>

#include <string>

namespace shadyloc::datasets
{
/** Rectified stereo calibration from an .ini file, read strictly (unknown
 * sections and keys are errors):
 *   [left]   fx_px fy_px cx_px cy_px
 *   [right]  fx_px fy_px cx_px cy_px  (any key missing here: the left value)
 *   [stereo] baseline_m, width_px, height_px
 * The keys fx, fy, cx, cy, width, height of earlier versions are refused
 * with their new names.
 */
struct TFolderCalib : public mrpt::config::CLoadableOptions
{
	double fx_l = 0, fy_l = 0, cx_l = 0, cy_l = 0;	//!< left intrinsics [px]
	double fx_r = 0, fy_r = 0, cx_r = 0, cy_r = 0;	//!< right intrinsics [px]
	double baseline_m = 0;	//!< right camera at +baseline_m along the left x axis [m]
	uint32_t width = 0, height = 0;	 //!< image size every image must have [px]

	/** The keys of one camera's section, [left] or [right] (its intrinsics),
	 * declared once (core/Options.h). */
	struct TCameraKeys
	{
		double &fx, &fy, &cx, &cy;
		void keys(core::KeyVisitor& v);
	};
	/** The keys of [stereo]. */
	struct TStereoKeys
	{
		double& baseline_m;
		uint32_t &width, &height;
		void keys(core::KeyVisitor& v);
	};
	TCameraKeys leftKeys() { return {fx_l, fy_l, cx_l, cy_l}; }
	TCameraKeys rightKeys() { return {fx_r, fy_r, cx_r, cy_r}; }
	TStereoKeys stereoKeys() { return {baseline_m, width, height}; }

	/** `section` is ignored (the file has its own sections); throws
	 * core::SettingsError naming the file, section and key that is missing,
	 * unknown or invalid. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& section) override;
	void dumpToTextStream(std::ostream& out) const override;
	/** Loads a file; DatasetError naming the file, section and key. */
	static TFolderCalib FromFile(const std::string& iniPath);
	/** Each camera as MRPT's model: its intrinsics, the image size, no distortion. */
	mrpt::img::TCamera leftCamera() const;
	mrpt::img::TCamera rightCamera() const;
};

/** Folder import. Timestamps: times file (one per line, first column [s]; as
 * many as pairs) if given, else startTime + i / rateHz. */
class FolderImporter : public mrpt::system::COutputLogger
{
   public:
	FolderImporter();
	TImportOptions options;
	double rateHz = 0;	 //!< frame rate when no times file [Hz]
	double startTime = 0;  //!< timestamp of frame 0 with rateHz [s since Unix epoch]
	std::string timesFile;	//!< "" = use rateHz

	TImportResult run(
		const std::string& leftDir, const std::string& rightDir, const std::string& calibIni,
		const std::string& outRawlog);
};

/** Image files (png, jpg, jpeg, ppm, pgm, bmp, tif, tiff; any case) in a
 * directory, sorted by name. Throws DatasetError if the directory is missing. */
std::vector<std::string> listImages(const std::string& dir);

}  // namespace shadyloc::datasets
