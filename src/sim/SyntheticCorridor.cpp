/* ShadyLoc — ray-cast textured corridor for VO tests. */
#include <shadyloc/sim/Noise.h>
#include <shadyloc/sim/SyntheticCorridor.h>

#include <opencv2/core.hpp>

#include <cmath>
#include <limits>

namespace shadyloc::sim
{
namespace
{
uint32_t hash3(int32_t a, int32_t b, uint32_t c)
{
	return sim::hash32(static_cast<uint32_t>(a) * 0x8da6b343u ^ static_cast<uint32_t>(b) * 0xd8163841u ^ c * 0xcb1ab31fu);
}
/** Random colour (B, G, R in [25, 230]) of a texture cell. */
Eigen::Vector3d cellColour(double a, double b, double cell, uint32_t salt)
{
	const int32_t ia = static_cast<int32_t>(std::floor(a / cell)), ib = static_cast<int32_t>(std::floor(b / cell));
	const uint32_t h = hash3(ia, ib, salt);
	return Eigen::Vector3d(25 + (h & 0xff) * 205.0 / 255, 25 + ((h >> 8) & 0xff) * 205.0 / 255,
		25 + ((h >> 16) & 0xff) * 205.0 / 255);
}
}  // namespace

SyntheticCorridor::SyntheticCorridor(const TCorridorOptions& o) : m_o(o) {}

geometry::TStereoCalib SyntheticCorridor::calib() const
{
	geometry::TStereoCalib c;
	c.fx = c.fy = m_o.fx;
	c.cx = c.cxR = (m_o.width - 1) / 2.0;
	c.cy = (m_o.height - 1) / 2.0;
	c.baseline = m_o.baseline;
	return c;
}

double SyntheticCorridor::intersect(const Eigen::Vector3d& O, const Eigen::Vector3d& d, int& plane) const
{
	double best = std::numeric_limits<double>::infinity();
	plane = -1;
	auto test = [&](double o, double dd, double wall, int id) {
		if (std::abs(dd) < 1e-12) return;
		const double t = (wall - o) / dd;
		if (t > 1e-6 && t < best)
		{
			best = t;
			plane = id;
		}
	};
	test(O.x(), d.x(), -m_o.half_width, 0);
	test(O.x(), d.x(), m_o.half_width, 1);
	test(O.y(), d.y(), -m_o.half_height, 2);
	test(O.y(), d.y(), m_o.half_height, 3);
	test(O.z(), d.z(), m_o.length, 4);
	test(O.z(), d.z(), -m_o.length, 5);
	return best;
}

double SyntheticCorridor::depth(const Eigen::Isometry3d& T, double u, double v) const
{
	const geometry::TStereoCalib c = calib();
	const Eigen::Vector3d dc((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);  // z = 1 in the camera
	int plane;
	const double t = intersect(T.translation(), T.linear() * dc, plane);
	return plane < 0 ? 0.0 : t;	 // with dc.z = 1, the ray parameter is the depth
}

Eigen::Vector3d SyntheticCorridor::shade(const Eigen::Vector3d& O, const Eigen::Vector3d& d) const
{
	int plane;
	const double best = intersect(O, d, plane);
	if (plane < 0) return Eigen::Vector3d(0, 0, 0);
	const Eigen::Vector3d P = O + best * d;
	double a, b;
	if (plane <= 1)
		a = P.z(), b = P.y();
	else if (plane <= 3)
		a = P.x(), b = P.z();
	else
		a = P.x(), b = P.y();
	const uint32_t salt = m_o.seed * 16u + static_cast<uint32_t>(plane);
	return 0.6 * cellColour(a, b, m_o.coarse_cell, salt) + 0.4 * cellColour(a + 0.013, b + 0.029, m_o.fine_cell, salt + 8);
}

void SyntheticCorridor::renderEye(const Eigen::Isometry3d& T, cv::Mat& out, uint32_t noiseSeed) const
{
	out.create(m_o.height, m_o.width, CV_8UC3);
	const geometry::TStereoCalib c = calib();
	const int S = std::max(1, m_o.supersample);
	const Eigen::Vector3d O = T.translation();
	const Eigen::Matrix3d R = T.linear();
	cv::RNG rng(noiseSeed * 7919u + 17u);
	for (int v = 0; v < m_o.height; v++)
	{
		auto* row = out.ptr<cv::Vec3b>(v);
		for (int u = 0; u < m_o.width; u++)
		{
			Eigen::Vector3d acc(0, 0, 0);
			for (int sy = 0; sy < S; sy++)
				for (int sx = 0; sx < S; sx++)
				{
					const double pu = u - 0.5 + (sx + 0.5) / S, pv = v - 0.5 + (sy + 0.5) / S;
					const Eigen::Vector3d d = R * Eigen::Vector3d((pu - c.cx) / c.fx, (pv - c.cy) / c.fy, 1.0);
					acc += shade(O, d);
				}
			acc /= S * S;
			for (int k = 0; k < 3; k++)
			{
				const double n = m_o.noise_sigma > 0 ? rng.gaussian(m_o.noise_sigma) : 0.0;
				row[u][k] = cv::saturate_cast<uint8_t>(acc(k) + n);
			}
		}
	}
}

void SyntheticCorridor::render(
	const Eigen::Isometry3d& T_world_left, cv::Mat& leftBGR, cv::Mat& rightBGR, uint32_t noiseSeed) const
{
	renderEye(T_world_left, leftBGR, 2 * noiseSeed);
	Eigen::Isometry3d T_left_right = Eigen::Isometry3d::Identity();
	T_left_right.translation().x() = m_o.baseline;
	renderEye(T_world_left * T_left_right, rightBGR, 2 * noiseSeed + 1);
}

Eigen::Isometry3d SyntheticCorridor::examplePose(int k, double speed)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.translation() = Eigen::Vector3d(0.4 * std::sin(0.09 * k), 0.15 * std::sin(0.06 * k + 0.5), speed * k);
	const double yaw = 6.0 * M_PI / 180 * std::sin(0.07 * k), pitch = 2.0 * M_PI / 180 * std::sin(0.05 * k);
	T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
				  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()))
					 .toRotationMatrix();
	return T;
}

}  // namespace shadyloc::sim
