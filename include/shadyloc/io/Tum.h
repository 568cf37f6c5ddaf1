/* ShadyLoc — TUM trajectory files: one pose per line,
 *   timestamp tx ty tz qx qy qz qw
 * (seconds; metres; unit quaternion, scalar last), '#' starts a comment.
 * Format of the TUM RGB-D benchmark (Sturm et al., IROS 2012). The one TUM
 * reader and writer of the library. */
#pragma once

#include <shadyloc/io/Trajectory.h>

#include <string>

namespace shadyloc::io
{
/** Reads a TUM file in file order (io::sortByTime() sorts). Blank lines and
 * lines starting with '#' are skipped; quaternions are normalised (a norm off
 * by more than 1% is an error). Throws std::runtime_error naming "file:line"
 * on any bad line. */
Trajectory readTum(const std::string& path);

/** Writes a TUM file atomically (no half-written file on failure): times and
 * translations with 9 decimals (ns, nm), quaternions with 9 decimals and
 * qw >= 0. An optional header comment (without '#') goes on the first line. */
void writeTum(const std::string& path, const Trajectory& traj, const std::string& comment = "");

/** The TUM text of one pose (no newline), as writeTum() writes it. */
std::string tumLine(const TStampedPose& p);

}  // namespace shadyloc::io
