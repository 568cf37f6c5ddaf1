/* ShadyLoc — the concrete observation filters. */
#pragma once

#include <shadyloc/filters/CObservationFilter.h>
#include <shadyloc/image/ColourTransforms.h>

#include <memory>

namespace shadyloc
{
/** RGB -> monochrome (BT.601 luma): the baseline channel. Grey input is
 * passed through as is. Default suffix "_mono". */
class CFilterMonochrome : public CObservationFilter
{
	DEFINE_SERIALIZABLE(CFilterMonochrome, shadyloc)
   public:
	CFilterMonochrome();
	image::ChannelOrder order = image::ChannelOrder::BGR;  //!< of stored images
	void transformImage(const cv::Mat& in, cv::Mat& out) const override;
	void keys(core::KeyVisitor& v) override;
};

/** RGB -> illumination-invariant (McManus et al. 2014, eq. 1), fast table
 * path, both eyes on two threads. Default suffix "_inv". Colour input only. */
class CFilterInvariant : public CObservationFilter
{
	DEFINE_SERIALIZABLE(CFilterInvariant, shadyloc)
   public:
	CFilterInvariant();
	const image::InvariantParams& params() const { return m_params; }
	void setParams(const image::InvariantParams& p);
	bool parallel_eyes = true;	//!< transform left and right on two threads

	std::string describe() const override { return m_params.asString(); }
	/** Same class and InvariantParams::sameImageAs (parallel_eyes aside). */
	bool sameImagesAs(const CObservationFilter& o) const override;

	void transformImages(const std::vector<cv::Mat>& in, std::vector<cv::Mat>& out) const override;
	void transformImage(const cv::Mat& in, cv::Mat& out) const override;
	/** InvariantParams' keys, then parallel_eyes. */
	void keys(core::KeyVisitor& v) override;
	void validate() const override;

   protected:
	/** As InvariantParams::readFrom (peak wavelengths instead of alpha and
	 * beta; offset's default), then parallel_eyes. */
	void loadSpecificOptions(core::SettingsSection& s) override;
	/** parallel_eyes; gamma unless linearisation = gamma; the knees and tail
	 * slopes without compressed tails (so that linear-mapping channels keep
	 * the text that maps made before the tails existed recorded). */
	std::vector<std::string> keysNotDecidingImages() const override;
	void onOptionsChanged() override;

   private:
	image::InvariantParams m_params;
	std::shared_ptr<image::InvariantTransform> m_transform;
};

/** Undoes the camera's gamma encoding (sRGB curve or a power law), 8-bit
 * out. Default suffix "_lin". Colour input only. */
class CFilterLinearise : public CObservationFilter
{
	DEFINE_SERIALIZABLE(CFilterLinearise, shadyloc)
   public:
	CFilterLinearise();
	image::Linearisation linearisation = image::Linearisation::SRGB;
	double gamma = 2.2;	 //!< exponent when linearisation = gamma
	void transformImage(const cv::Mat& in, cv::Mat& out) const override;
	void keys(core::KeyVisitor& v) override;
	/** gamma in (0, 10) with linearisation = gamma. */
	void validate() const override;

   protected:
	/** gamma unless linearisation = gamma. */
	std::vector<std::string> keysNotDecidingImages() const override;
};

}  // namespace shadyloc
