/* ShadyLoc — the reason inside an MRPT exception's text. */
#pragma once

#include <string>

namespace shadyloc::core
{
/** What went wrong, without MRPT's dressing. MRPT exceptions print a banner,
 * "Message: <why>", "Location:" lines and call-stack traces, and a wrapped
 * exception (MRPT wraps every error raised while reading a nested object)
 * appears after "Original exception:"; the innermost one says what is wrong.
 * Text that is not an MRPT exception's is returned as it is. */
std::string mrptReason(const std::string& what);
}  // namespace shadyloc::core
