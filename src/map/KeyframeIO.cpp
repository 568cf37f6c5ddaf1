/* ShadyLoc — keyframe serialisation. */
#include <shadyloc/map/KeyframeIO.h>

#include <mrpt/io/CStream.h>

#include <string>

namespace shadyloc::map
{
namespace
{
template <class Derived>
void writeMat(mrpt::serialization::CArchive& out, const Eigen::MatrixBase<Derived>& M)
{
	for (Eigen::Index i = 0; i < M.rows(); i++)
		for (Eigen::Index j = 0; j < M.cols(); j++) out << M(i, j);
}
constexpr uint8_t kDescriptorWords = std::tuple_size_v<decltype(features::TBriefDescriptor::w)>;
}  // namespace

void writePose(mrpt::serialization::CArchive& out, const Eigen::Isometry3d& T)
{
	writeMat(out, T.matrix().topRows<3>());
}

void readPose(io::BoundedReader& in, Eigen::Isometry3d& T, const char* field)
{
	Eigen::Matrix<double, 3, 4> M;
	in.readMatrix(M, field);
	T.setIdentity();
	T.matrix().topRows<3>() = M;
}

void writeMeasurement(mrpt::serialization::CArchive& out, const features::TStereoMeasurement& m)
{
	out << m.uL << m.v << m.uR << m.response << m.zncc;
	for (uint64_t w : m.desc.w) out << w;
	out.WriteBuffer(m.patch.data(), m.patch.size());
	writeMat(out, m.P);
	writeMat(out, m.cov);
}

void readMeasurement(io::BoundedReader& in, features::TStereoMeasurement& m)
{
	in.read(m.uL, "measurement uL");
	in.read(m.v, "measurement v");
	in.read(m.uR, "measurement uR");
	in.read(m.response, "measurement response");
	in.read(m.zncc, "measurement zncc");
	for (uint64_t& w : m.desc.w) in.read(w, "measurement descriptor");
	in.readBytes(m.patch.data(), m.patch.size(), "measurement patch");
	in.readMatrix(m.P, "measurement P");
	in.readMatrix(m.cov, "measurement cov");
}

void writeKeyframe(mrpt::serialization::CArchive& out, const TKeyframe& kf)
{
	out << kKeyframeFormatVersion << static_cast<uint8_t>(features::kPatchSize) << kDescriptorWords
		<< kf.id << static_cast<uint64_t>(kf.frame) << kf.timestamp << kf.chain_break;
	writePose(out, kf.T_prevkf_kf);
	writePose(out, kf.T_world_kf);
	writeMat(out, kf.cov);
	out << static_cast<uint32_t>(kf.meas.size());
	for (const auto& m : kf.meas) writeMeasurement(out, m);
}

void readKeyframe(io::BoundedReader& in, TKeyframe& kf)
{
	const uint8_t version = in.read<uint8_t>("format version");
	if (version != kKeyframeFormatVersion)
		in.fail(
			"format version", "unknown keyframe format version " + std::to_string(version) +
								  " (this build reads " + std::to_string(kKeyframeFormatVersion) + ")");
	const uint8_t patch = in.read<uint8_t>("patch side");
	if (patch != features::kPatchSize)
		in.fail(
			"patch side", "measurements carry " + std::to_string(patch) + "x" + std::to_string(patch) +
							  " patches, this build uses " + std::to_string(features::kPatchSize));
	const uint8_t words = in.read<uint8_t>("descriptor words");
	if (words != kDescriptorWords)
		in.fail(
			"descriptor words", std::to_string(64 * words) + "-bit descriptors, this build uses " +
									std::to_string(64 * kDescriptorWords));
	TKeyframe k;
	in.read(k.id, "id");
	k.frame = static_cast<size_t>(in.read<uint64_t>("frame"));
	in.read(k.timestamp, "timestamp");
	in.read(k.chain_break, "chain_break");
	readPose(in, k.T_prevkf_kf, "T_prevkf_kf");
	readPose(in, k.T_world_kf, "T_world_kf");
	in.readMatrix(k.cov, "cov");
	k.meas.resize(in.readCount("measurement count", kMeasurementBytes));
	for (auto& m : k.meas) readMeasurement(in, m);
	kf = std::move(k);	// all or nothing: kf is untouched on error
}

void readKeyframe(mrpt::io::CStream& s, TKeyframe& kf, uint64_t budgetBytes, const std::string& what)
{
	auto ar = mrpt::serialization::archiveFrom(s);
	io::BoundedReader in(
		ar, what, io::BoundedReader::remainingBytes(s, budgetBytes), io::BoundedReader::positionOf(s));
	readKeyframe(in, kf);
}

void readKeyframe(
	mrpt::serialization::CArchive& ar, TKeyframe& kf, uint64_t budgetBytes, const std::string& what)
{
	io::BoundedReader in(ar, what, budgetBytes);
	readKeyframe(in, kf);
}

}  // namespace shadyloc::map
