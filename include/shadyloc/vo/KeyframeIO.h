/* ShadyLoc — binary (MRPT CArchive) serialisation of stereo measurements and
 * keyframes, versioned, for the survey map to store VO keyframes. */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/serialization/CArchive.h>

namespace shadyloc::vo
{
/** Current format version written by writeKeyframe(). */
constexpr uint8_t kKeyframeFormatVersion = 0;

void writeMeasurement(mrpt::serialization::CArchive& out, const features::TStereoMeasurement& m);
/** Throws std::runtime_error on an unknown version. */
void readMeasurement(mrpt::serialization::CArchive& in, features::TStereoMeasurement& m, uint8_t version);

/** Keyframe with all its measurements; starts with a format version byte. */
void writeKeyframe(mrpt::serialization::CArchive& out, const TKeyframe& kf);
void readKeyframe(mrpt::serialization::CArchive& in, TKeyframe& kf);

}  // namespace shadyloc::vo
