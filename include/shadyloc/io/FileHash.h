/* ShadyLoc — FNV-1a (64 bit) of a file's bytes or of a text, as 16 hex
 * digits: what the evaluation's provenance records of its inputs (a map, a
 * rawlog, a config, a run list), so that a result names exactly what it was
 * computed from. A fingerprint, not a cryptographic hash. */
#pragma once

#include <string>

namespace shadyloc::io
{
/** Of a file's bytes; throws std::runtime_error naming an unreadable file. */
std::string fnv1a64File(const std::string& path);
/** Of a text. */
std::string fnv1a64(const std::string& text);

}  // namespace shadyloc::io
