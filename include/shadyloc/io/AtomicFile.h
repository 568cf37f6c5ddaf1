/* ShadyLoc — write-then-rename, so a failed run leaves no half-written file. */
#pragma once

#include <functional>
#include <string>

namespace shadyloc::io
{
/** Calls write(tmpPath) with a temporary path beside `path` (same directory,
 * same extension so format-by-extension writers such as cv::imwrite work),
 * then renames it onto `path`. If write throws, the temporary file is removed
 * and the exception propagates. A command with several outputs, or with
 * inputs an output must not replace, uses an io::OutputTransaction. */
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

/** Writes `text` to `path` atomically (writeAtomically), throwing naming the file. */
void writeTextFile(const std::string& path, const std::string& text);

/** Temporary sibling of `path` keeping its extension: "dir/.stem.tmp-<pid>.ext". */
std::string temporarySibling(const std::string& path);

}  // namespace shadyloc::io
