/* ShadyLoc — the evaluation's JSON files (private to the eval area:
 * nlohmann-json stays out of the public headers). A document is built as a
 * nlohmann::ordered_json (members in the order written), strings and
 * integers are written by the library; two things are ours, because the
 * formats are compared byte for byte and were fixed before the library:
 *
 *  - numbers with a fixed count of decimals per field ("0.500000", "12.250"),
 *    where the library prints a double's shortest round trip ("0.5");
 *  - the layout: containers on one line ({"a": 1, "b": [2, 3]}), those named
 *    by the writer one member a line.
 *
 * Reading is the library's alone (readJsonFile).
 */
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace shadyloc::eval
{
using Json = nlohmann::ordered_json;

/** A number written with `decimals` decimals, as printf's "%.*f" writes it;
 * null if not finite. It is carried in the document as its text (a binary
 * value of its own subtype, which only writeJson knows), so that the
 * decimals survive until the document is written. */
Json fixedNumber(double v, int decimals = 6);

/** The text of `doc`: every object and array on one line, members separated
 * by ", " and keys by ": ", except the containers whose JSON pointers are in
 * `broken` ("" the document itself): one member a line, indented two spaces
 * for each broken container around it, the closing bracket on its own line.
 * Ends with a newline. */
std::string writeJson(const Json& doc, const std::vector<std::string>& broken);

/** The JSON document in a file; null when the file is missing or is not JSON. */
Json readJsonFile(const std::string& path);

}  // namespace shadyloc::eval
