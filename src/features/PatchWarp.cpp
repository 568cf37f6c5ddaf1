/* ShadyLoc — patches that follow the viewpoint (PatchWarp.h). */
#include <shadyloc/features/PatchWarp.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <utility>

namespace shadyloc::features
{
namespace
{
Eigen::Matrix3d intrinsics(const geometry::TStereoCalib& c)
{
	Eigen::Matrix3d K;
	K << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1;
	return K;
}

/** std::lround clamped to +-4096, without the library call (a warped
 * pattern rounds 512 offsets): the truncation, and a step away from zero
 * where the dropped fraction (exact: Sterbenz) is at least a half. */
int roundOffset(double x)
{
	if (!(std::abs(x) < 4096.0)) return x > 0 ? 4096 : -4096;
	int t = static_cast<int>(x);
	const double f = x - t;
	if (f >= 0.5)
		t++;
	else if (f <= -0.5)
		t--;
	return t;
}
}  // namespace

bool planeInducedAffine(
	const geometry::TStereoCalib& calibKf, const geometry::TStereoCalib& calib, const Eigen::Isometry3d& T_curr_kf,
	const Eigen::Vector3d& P_kf, const Eigen::Vector3d& n_kf, Eigen::Matrix2d& A, double max_stretch)
{
	const double rho = n_kf.dot(P_kf);
	const Eigen::Vector3d P_c = T_curr_kf * P_kf;
	if (!(P_kf.z() > 0.1 && P_c.z() > 0.1) || !(std::abs(rho) > 1e-6)) return false;
	// X_curr = R X_kf + t = (R + t n^T / rho) X_kf on the plane n^T X_kf = rho.
	const Eigen::Matrix3d H = intrinsics(calib) *
							  (T_curr_kf.linear() + T_curr_kf.translation() * n_kf.transpose() / rho) *
							  intrinsics(calibKf).inverse();
	const Eigen::Vector3d x(calibKf.fx * P_kf.x() / P_kf.z() + calibKf.cx, calibKf.fy * P_kf.y() / P_kf.z() + calibKf.cy, 1);
	const Eigen::Vector3d h = H * x;
	if (!(h.z() > 1e-9)) return false;
	// d(h1/h3, h2/h3) / d(u, v).
	for (int r = 0; r < 2; r++)
		for (int c = 0; c < 2; c++) A(r, c) = (H(r, c) * h.z() - h(r) * H(2, c)) / (h.z() * h.z());
	const Eigen::Vector2d s = Eigen::JacobiSVD<Eigen::Matrix2d>(A).singularValues();
	return A.allFinite() && s(0) <= max_stretch && s(1) >= 1.0 / max_stretch;
}

double warpDistortion(const Eigen::Matrix2d& A) { return (A - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff(); }

WarpedBriefPattern::WarpedBriefPattern(const BriefExtractor& brief, const Eigen::Matrix2d& A)
{
	// A times each offset, written out in the order Eigen's product sums it
	// (the same values), rounded; built for every warped landmark searched.
	const double a00 = A(0, 0), a01 = A(0, 1), a10 = A(1, 0), a11 = A(1, 1);
	const auto& p = brief.pattern();
	const size_t n = std::min(p.size(), m_pattern.size());
	int reach = 0;
	for (size_t i = 0; i < n; i++)
		for (int k = 0; k < 4; k += 2)
		{
			const double px = p[i][k], py = p[i][k + 1];
			const int dx = roundOffset(a00 * px + a01 * py), dy = roundOffset(a10 * px + a11 * py);
			m_pattern[i][k] = static_cast<int16_t>(dx);
			m_pattern[i][k + 1] = static_cast<int16_t>(dy);
			reach = std::max({reach, std::abs(dx), std::abs(dy)});
		}
	m_reach = reach;
}

bool WarpedBriefPattern::compute(const cv::Mat& img, int x, int y, TBriefDescriptor& d) const
{
	if (x < m_reach || y < m_reach || x >= img.cols - m_reach || y >= img.rows - m_reach) return false;
	briefTests(img.ptr<uint8_t>(y) + x, static_cast<ptrdiff_t>(img.step[0]), m_pattern, d);
	return true;
}

bool locateWarpedPatch(
	const std::array<uint8_t, kPatchSize * kPatchSize>& patch, const cv::Mat& img, int x0, int y0,
	const Eigen::Matrix2d& A, int radius_px, float min_zncc, int iterations, float& x, float& y)
{
	// The keyframe's pixel grid around (x0, y0): the patch, its search
	// radius and the margin refinePatch2D's cubic interpolation reads.
	const int half = kPatchSize / 2 + radius_px + 4, side = 2 * half + 1;
	// (x0, y0) + A (c - half, r - half), written out (an Eigen temporary
	// returned from here trips GCC 12's uninitialised-value warning).
	const auto at = [&](int c, int r) {
		const double dc = c - half, dr = r - half;
		return std::pair<double, double>(x0 + (A(0, 0) * dc + A(0, 1) * dr), y0 + (A(1, 0) * dc + A(1, 1) * dr));
	};
	// An affine map takes the grid's extremes to its corners: when they read
	// inside the image, every pixel does, and the truncating casts below are
	// floor and round (the coordinates and values are >= 0). Hot: a call
	// to floor or lround per pixel cost more than the interpolation.
	for (const int c : {0, side - 1})
		for (const int r : {0, side - 1})
		{
			const auto [px, py] = at(c, r);
			if (!(px >= 0 && py >= 0 && std::floor(px) + 1 < img.cols && std::floor(py) + 1 < img.rows)) return false;
		}
	cv::Mat local(side, side, CV_8UC1);
	for (int r = 0; r < side; r++)
	{
		uint8_t* row = local.ptr<uint8_t>(r);
		for (int c = 0; c < side; c++)
		{
			const auto [px, py] = at(c, r);
			const int ix = static_cast<int>(px), iy = static_cast<int>(py);
			const double fx = px - ix, fy = py - iy;
			const uint8_t* a = img.ptr<uint8_t>(iy) + ix;
			const uint8_t* b = img.ptr<uint8_t>(iy + 1) + ix;
			const double v = (1 - fy) * ((1 - fx) * a[0] + fx * a[1]) + fy * ((1 - fx) * b[0] + fx * b[1]);
			row[c] = static_cast<uint8_t>(v + 0.5);
		}
	}
	float xl, yl;
	if (!locatePatch(patch, local, half, half, radius_px, min_zncc, iterations, xl, yl)) return false;
	const Eigen::Vector2d p = Eigen::Vector2d(x0, y0) + A * Eigen::Vector2d(xl - half, yl - half);
	x = static_cast<float>(p.x());
	y = static_cast<float>(p.y());
	return true;
}

}  // namespace shadyloc::features
