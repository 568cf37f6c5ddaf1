/* ShadyLoc — binary (MRPT CArchive) serialisation of stereo measurements and
 * keyframes: versioned, read with bounds (io::BoundedReader), for the survey
 * map. The layout is documented in docs/architecture.md ("Persistent
 * formats") and pinned by tests/golden/keyframe.bin. */
#pragma once

#include <shadyloc/io/BoundedReader.h>
#include <shadyloc/map/Keyframe.h>

#include <mrpt/serialization/CArchive.h>

#include <cstdint>
#include <string>

namespace mrpt::io
{
class CStream;
}

namespace shadyloc::map
{
/** Format version written by writeKeyframe(). 1: a header with the patch
 * side and descriptor size the measurements were made with (0, without it,
 * was never stored anywhere and is refused). */
constexpr uint8_t kKeyframeFormatVersion = 1;

/** Bytes of one measurement on disk: uL, v, uR, response, zncc (float32),
 * BRIEF (4 x uint64), patch (kPatchSize^2 bytes), P (3 float64), cov (3x3 float64). */
constexpr size_t kMeasurementBytes = 5 * 4 + 4 * 8 + features::kPatchSize * features::kPatchSize + 3 * 8 + 9 * 8;

/** Largest keyframe a reader accepts when the stream cannot tell its own
 * remaining size (a gz stream, an archive inside another object) [bytes]:
 * 64 MiB, about 290,000 measurements (a VO keyframe has a few hundred). */
constexpr uint64_t kMaxKeyframeBytes = 64ull << 20;

void writeMeasurement(mrpt::serialization::CArchive& out, const features::TStereoMeasurement& m);
void readMeasurement(io::BoundedReader& in, features::TStereoMeasurement& m);

/** An Isometry3d as its top 3x4 rows, row-major float64. */
void writePose(mrpt::serialization::CArchive& out, const Eigen::Isometry3d& T);
void readPose(io::BoundedReader& in, Eigen::Isometry3d& T, const char* field);

/** A keyframe with all its measurements; starts with the format version byte. */
void writeKeyframe(mrpt::serialization::CArchive& out, const TKeyframe& kf);
/** Reads what writeKeyframe() wrote; throws io::CorruptDataError naming the
 * reader's object and the byte offset on an unknown version, a header that
 * does not match this build (patch side, descriptor size), a measurement
 * count beyond the remaining bytes, or a truncated stream. */
void readKeyframe(io::BoundedReader& in, TKeyframe& kf);
/** From a stream: bounded by its remaining size when it knows it (file,
 * memory), else by `budgetBytes`; offsets in errors are stream positions. */
void readKeyframe(
	mrpt::io::CStream& in, TKeyframe& kf, uint64_t budgetBytes = kMaxKeyframeBytes,
	const std::string& what = "keyframe");
/** From an archive whose stream is not at hand: bounded by `budgetBytes`,
 * offsets in errors count from here. */
void readKeyframe(
	mrpt::serialization::CArchive& in, TKeyframe& kf, uint64_t budgetBytes = kMaxKeyframeBytes,
	const std::string& what = "keyframe");

}  // namespace shadyloc::map
