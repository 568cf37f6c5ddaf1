/* ShadyLoc — JSON text of the evaluation's outputs (private to the eval area). */
#pragma once

#include <string>

namespace shadyloc::eval
{
/** A JSON string literal; a number with `prec` decimals ("null" if not finite). */
std::string jsonString(const std::string& s);
std::string jsonNumber(double v, int prec = 6);

}  // namespace shadyloc::eval
