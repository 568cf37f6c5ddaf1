/* ShadyLoc — TUM trajectory files: one pose per line,
 *   timestamp tx ty tz qx qy qz qw
 * (seconds; metres; unit quaternion, scalar last), '#' starts a comment.
 * Format of the TUM RGB-D benchmark (Sturm et al., IROS 2012). */
#pragma once

#include <mrpt/poses/CPose3D.h>

#include <string>
#include <vector>

namespace shadyloc::datasets
{
/** One timestamped pose. The frames are the file's: usually T_world_body. */
struct TTimedPose
{
	double t = 0;				  //!< timestamp [s]
	mrpt::poses::CPose3D pose;  //!< the pose at t
};
using TTrajectory = std::vector<TTimedPose>;

/** Reads a TUM file in file order. Blank lines and lines starting with '#'
 * are skipped; quaternions are normalised (a norm off by more than 1% is an
 * error). Throws std::runtime_error naming "file:line" on any bad line, and
 * naming the file if it is missing, a directory or holds no pose. */
TTrajectory readTum(const std::string& path);

/** Writes a TUM file atomically (no half-written file on failure): times and
 * translations with 9 decimals (ns, nm), quaternions with 9 decimals and
 * qw >= 0. An optional header comment (without '#') goes on the first line. */
void writeTum(const std::string& path, const TTrajectory& traj, const std::string& comment = "");

/** The TUM text of one pose (no newline), as writeTum() writes it. */
std::string tumLine(const TTimedPose& p);

}  // namespace shadyloc::datasets
