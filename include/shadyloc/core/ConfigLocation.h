/* ShadyLoc — where in the config files a setting named by an error lies.
 *
 * Several -c files are layered into one text before the strict settings
 * reader sees them, so its errors name section and key but not the file or
 * line; these functions find them again, for the commands that take layered
 * configs (localise, eval). */
#pragma once

#include <string>
#include <vector>

namespace shadyloc::core
{
/** "file:line" of `[section]` (key empty) or of `key = ...` in that
 * section, the last file that sets it winning (later files override); ""
 * if not found. */
std::string locateSetting(const std::vector<std::string>& files, const std::string& section, const std::string& key);

/** `msg` (an error naming "[section] key:") prefixed by the file and line of
 * that setting, else by "config <what>". */
std::string configError(const std::vector<std::string>& files, const std::string& what, const std::string& msg);

}  // namespace shadyloc::core
