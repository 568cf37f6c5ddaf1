/* ShadyLoc — shadow visibility metrics. */
#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/image/ShadowMetrics.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace shadyloc::image
{
namespace
{
double median(std::vector<double> v)
{
	if (v.empty()) return 0;
	auto mid = v.begin() + v.size() / 2;
	std::nth_element(v.begin(), mid, v.end());
	return *mid;
}
}  // namespace

cv::Mat shadowMaskFromPair(const cv::Mat& freeBgr, const cv::Mat& shadowBgr, const ShadowMaskOptions& o)
{
	if (freeBgr.type() != CV_8UC3 || shadowBgr.type() != CV_8UC3 || freeBgr.size() != shadowBgr.size())
		throw std::invalid_argument("shadow mask: needs two 8-bit colour images of equal size");
	double logLin[256];
	for (int v = 0; v < 256; v++) logLin[v] = std::log(linearise(v, Linearisation::SRGB, 0));
	cv::Mat mask(freeBgr.size(), CV_8U, cv::Scalar(0));
	for (int y = 0; y < freeBgr.rows; y++)
	{
		const auto* f = freeBgr.ptr<cv::Vec3b>(y);
		const auto* s = shadowBgr.ptr<cv::Vec3b>(y);
		auto* m = mask.ptr<uint8_t>(y);
		for (int x = 0; x < freeBgr.cols; x++)
		{
			bool in = true;
			for (int c = 0; c < 3 && in; c++)
				in = f[x][c] >= o.minCode && logLin[f[x][c]] - logLin[s[x][c]] > o.minLogDrop;
			m[x] = in ? 255 : 0;
		}
	}
	if (o.erodeRadius > 0)
		cv::erode(
			mask, mask,
			cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * o.erodeRadius + 1, 2 * o.erodeRadius + 1)));
	return mask;
}

ShadowStep relativeShadowStep(const cv::Mat& chFree, const cv::Mat& chShadow, const cv::Mat& mask)
{
	if (chFree.type() != CV_8U || chShadow.type() != CV_8U || mask.type() != CV_8U)
		throw std::invalid_argument("relativeShadowStep: needs 8-bit single-channel images");
	std::vector<double> freeValues, shadowValues;
	for (int y = 0; y < mask.rows; y++)
		for (int x = 0; x < mask.cols; x++)
			if (mask.at<uint8_t>(y, x))
			{
				freeValues.push_back(chFree.at<uint8_t>(y, x));
				shadowValues.push_back(chShadow.at<uint8_t>(y, x));
			}
	return relativeShadowStepOfValues(freeValues, shadowValues);
}

ShadowStep relativeShadowStepOfValues(const std::vector<double>& values, const std::vector<double>& shadow)
{
	if (values.size() != shadow.size())
		throw std::invalid_argument("relativeShadowStep: free and shadow value counts differ");
	if (values.size() < 100) throw std::invalid_argument("relativeShadowStep: shadow mask too small");
	std::vector<double> steps(values.size());
	for (size_t i = 0; i < values.size(); i++) steps[i] = std::abs(shadow[i] - values[i]);
	const double med = median(values);
	std::vector<double> dev(values.size());
	for (size_t i = 0; i < values.size(); i++) dev[i] = std::abs(values[i] - med);
	return {median(steps), 1.4826 * median(dev)};
}

}  // namespace shadyloc::image
