/* ShadyLoc — keyframe serialisation. */
#include <shadyloc/vo/KeyframeIO.h>

#include <stdexcept>
#include <string>

namespace shadyloc::vo
{
namespace
{
template <int R, int C>
void writeMat(mrpt::serialization::CArchive& out, const Eigen::Matrix<double, R, C>& M)
{
	for (int i = 0; i < R; i++)
		for (int j = 0; j < C; j++) out << M(i, j);
}
template <int R, int C>
void readMat(mrpt::serialization::CArchive& in, Eigen::Matrix<double, R, C>& M)
{
	for (int i = 0; i < R; i++)
		for (int j = 0; j < C; j++) in >> M(i, j);
}
void writePose(mrpt::serialization::CArchive& out, const Eigen::Isometry3d& T)
{
	const Eigen::Matrix<double, 3, 4> M = T.matrix().topRows<3>();
	writeMat(out, M);
}
void readPose(mrpt::serialization::CArchive& in, Eigen::Isometry3d& T)
{
	Eigen::Matrix<double, 3, 4> M;
	readMat(in, M);
	T.setIdentity();
	T.matrix().topRows<3>() = M;
}
}  // namespace

void writeMeasurement(mrpt::serialization::CArchive& out, const features::TStereoMeasurement& m)
{
	out << m.uL << m.v << m.uR << m.response << m.zncc;
	for (uint64_t w : m.desc.w) out << w;
	out.WriteBuffer(m.patch.data(), m.patch.size());
	Eigen::Matrix<double, 3, 1> P = m.P;
	writeMat(out, P);
	writeMat(out, Eigen::Matrix3d(m.cov));
}

void readMeasurement(mrpt::serialization::CArchive& in, features::TStereoMeasurement& m, uint8_t version)
{
	if (version != 0)
		throw std::runtime_error("stereo measurement: unknown format version " + std::to_string(version));
	in >> m.uL >> m.v >> m.uR >> m.response >> m.zncc;
	for (uint64_t& w : m.desc.w) in >> w;
	if (in.ReadBuffer(m.patch.data(), m.patch.size()) != m.patch.size())
		throw std::runtime_error("stereo measurement: truncated patch");
	Eigen::Matrix<double, 3, 1> P;
	readMat(in, P);
	m.P = P;
	Eigen::Matrix3d C;
	readMat(in, C);
	m.cov = C;
}

void writeKeyframe(mrpt::serialization::CArchive& out, const TKeyframe& kf)
{
	out << kKeyframeFormatVersion << kf.id << static_cast<uint64_t>(kf.frame) << kf.timestamp
		<< kf.chain_break;
	writePose(out, kf.T_prevkf_kf);
	writePose(out, kf.T_world_kf);
	writeMat(out, kf.cov);
	out << static_cast<uint32_t>(kf.meas.size());
	for (const auto& m : kf.meas) writeMeasurement(out, m);
}

void readKeyframe(mrpt::serialization::CArchive& in, TKeyframe& kf)
{
	uint8_t version;
	in >> version;
	if (version > kKeyframeFormatVersion)
		throw std::runtime_error("keyframe: unknown format version " + std::to_string(version));
	uint64_t frame;
	in >> kf.id >> frame >> kf.timestamp >> kf.chain_break;
	kf.frame = static_cast<size_t>(frame);
	readPose(in, kf.T_prevkf_kf);
	readPose(in, kf.T_world_kf);
	readMat(in, kf.cov);
	uint32_t n;
	in >> n;
	kf.meas.resize(n);
	for (auto& m : kf.meas) readMeasurement(in, m, version);
}

}  // namespace shadyloc::vo
