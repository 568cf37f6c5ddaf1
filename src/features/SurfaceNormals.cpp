/* ShadyLoc — surface normals of stereo measurements (SurfaceNormals.h). */
#include <shadyloc/features/SurfaceNormals.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <opencv2/calib3d.hpp>

#include <cmath>
#include <limits>

namespace shadyloc::features
{
cv::Mat denseDisparity(const cv::Mat& left8, const cv::Mat& right8, const TSurfaceNormalOptions& o)
{
	const int nd = (o.max_disparity_px + 15) / 16 * 16, bs = o.block_size_px;
	// P1, P2: the smoothness penalties OpenCV's documentation suggests for one channel.
	auto sgbm = cv::StereoSGBM::create(0, nd, bs, 8 * bs * bs, 32 * bs * bs, 1, 0, 10, 100, 1, cv::StereoSGBM::MODE_SGBM);
	cv::Mat d16, d;
	sgbm->compute(left8, right8, d16);
	d16.convertTo(d, CV_32F, 1.0 / 16);
	d.setTo(std::numeric_limits<float>::quiet_NaN(), d16 < 0);
	return d;
}

namespace
{
/** Least-squares plane d = c + a du + b dv through the samples whose flag is
 * set; false when singular. */
bool fitPlane(const std::vector<Eigen::Vector3d>& s, const std::vector<char>& use, Eigen::Vector3d& abc)
{
	Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
	Eigen::Vector3d r = Eigen::Vector3d::Zero();
	for (size_t i = 0; i < s.size(); i++)
	{
		if (!use[i]) continue;
		const Eigen::Vector3d x(s[i].x(), s[i].y(), 1.0);
		N += x * x.transpose();
		r += x * s[i].z();
	}
	const Eigen::LDLT<Eigen::Matrix3d> ldlt(N);
	if (ldlt.info() != Eigen::Success || !(std::abs(N.determinant()) > 1e-9)) return false;
	abc = ldlt.solve(r);
	return abc.allFinite();
}
}  // namespace

size_t estimateNormals(
	const cv::Mat& disp, const geometry::TStereoCalib& calib, const TSurfaceNormalOptions& o,
	std::vector<TStereoMeasurement>& meas)
{
	const int R = o.window_radius_px;
	const size_t needed = static_cast<size_t>(std::ceil(o.min_valid_fraction * (2 * R + 1) * (2 * R + 1)));
	size_t found = 0;
	std::vector<Eigen::Vector3d> s;
	std::vector<char> use;
	for (auto& m : meas)
	{
		m.normal.setZero();
		const int u0 = static_cast<int>(std::lround(m.uL)), v0 = static_cast<int>(std::lround(m.v));
		const double D = calib.disparity(m.uL, m.uR);
		if (u0 - R < 0 || v0 - R < 0 || u0 + R >= disp.cols || v0 + R >= disp.rows || !(D > 0)) continue;
		s.clear();
		for (int dv = -R; dv <= R; dv++)
			for (int du = -R; du <= R; du++)
			{
				const float d = disp.at<float>(v0 + dv, u0 + du);
				if (std::isfinite(d)) s.emplace_back(du, dv, d);
			}
		if (s.size() < needed) continue;
		use.assign(s.size(), 1);
		Eigen::Vector3d abc;	// (a, b, c) of d = a du + b dv + c
		if (!fitPlane(s, use, abc)) continue;
		size_t kept = 0;
		for (size_t i = 0; i < s.size(); i++)
			kept += use[i] = std::abs(abc.x() * s[i].x() + abc.y() * s[i].y() + abc.z() - s[i].z()) <= o.outlier_px;
		if (kept < needed || !fitPlane(s, use, abc)) continue;
		// The plane at the measurement itself (it sits at (uL, v), not at the integer centre).
		const double cAt = abc.z() + abc.x() * (m.uL - u0) + abc.y() * (m.v - v0) + calib.doffs();
		if (std::abs(cAt - D) > o.max_centre_error_px) continue;
		Eigen::Vector3d n(
			abc.x() * calib.fx, abc.y() * calib.fy, D - abc.x() * (m.uL - calib.cx) - abc.y() * (m.v - calib.cy));
		if (!(n.norm() > 1e-12)) continue;
		n.normalize();
		if (n.dot(m.P) > 0) n = -n;	 // facing the camera
		m.normal = n.cast<float>();
		found++;
	}
	return found;
}

}  // namespace shadyloc::features
