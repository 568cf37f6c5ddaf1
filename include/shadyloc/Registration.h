/* ShadyLoc — registration of the MRPT classes (the observation filters, the
 * keyframe map), in one place at the top of the library: the list names
 * classes of `filters` and `map`, so it lives above every area
 * (docs/architecture.md, "Class registration"). */
#pragma once

namespace shadyloc
{
/** Registers every RTTI/serialisable class of ShadyLoc with MRPT
 * (idempotent). Each class already registers itself when
 * libshadyloc_localisation loads; the MRPT plugin and the programs call this
 * again, which is harmless. */
void registerAllClasses();
}  // namespace shadyloc
