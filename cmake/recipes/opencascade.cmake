# OpenCASCADE from Debian's libocct-{foundation,modeling-data,modeling-algorithms}-dev, plus
# libocct-visualization-dev and libtbb-dev (see below why). Defines the interface target
# OpenCASCADE::OpenCASCADE with the toolkits HexMerge uses, or nothing when OCCT is not
# installed: the callers test `if(TARGET OpenCASCADE::OpenCASCADE)`. Returns early when a parent
# project already provides the target.
if(TARGET OpenCASCADE::OpenCASCADE)
  return()
endif()

# Only the three modules we use: without COMPONENTS, OCCT's config includes the targets of every
# module (Visualization, Draw...), whose -dev packages need not be installed.
find_package(OpenCASCADE CONFIG QUIET
  COMPONENTS FoundationClasses ModelingData ModelingAlgorithms)
if(NOT OpenCASCADE_FOUND OR NOT TARGET TKTopAlgo OR NOT TARGET TKShHealing OR NOT TARGET TKMesh)
  message(STATUS "OpenCASCADE not found: hexmerge_occ (the mesher from CAD, `hexmerge mesh`, "
                 "and regions by solid) is not built "
                 "(Debian: libocct-foundation-dev libocct-modeling-data-dev "
                 "libocct-modeling-algorithms-dev libocct-data-exchange-dev libocct-visualization-dev "
                 "libtbb-dev)")
  return()
endif()

# Debian's OCCT targets name libtbb.so and libtbbmalloc.so by absolute path; they come with
# libtbb-dev, which the OCCT -dev packages do not pull in. Check here rather than fail at link.
get_target_property(_hexmerge_occ_deps TKernel INTERFACE_LINK_LIBRARIES)
foreach(_dep IN LISTS _hexmerge_occ_deps)
  if(IS_ABSOLUTE "${_dep}" AND NOT EXISTS "${_dep}")
    message(WARNING "OpenCASCADE ${OpenCASCADE_VERSION} found but ${_dep} is missing "
                    "(Debian: libtbb-dev): hexmerge_occ is not built")
    return()
  endif()
endforeach()

# Debian 12's OCCT 7.6.3 ships NCollection_AliasedArray.hxx, which Poly_Triangulation.hxx (hence
# BRep_Tool.hxx and BRep_Builder.hxx) includes, in libocct-visualization-dev, not in
# libocct-foundation-dev.
if(NOT EXISTS "${OpenCASCADE_INCLUDE_DIR}/NCollection_AliasedArray.hxx"
   AND OpenCASCADE_VERSION VERSION_GREATER_EQUAL 7.6)
  message(WARNING "OpenCASCADE ${OpenCASCADE_VERSION} found but its header "
                  "NCollection_AliasedArray.hxx is missing (Debian 12: libocct-visualization-dev): "
                  "hexmerge_occ is not built")
  return()
endif()

# STEP and IGES readers (libocct-data-exchange-dev). Linked by file, not through OCCT's
# DataExchange component: that component's config also needs the OCAF and visualization -dev
# packages, for toolkits HexMerge does not use.
set(_hexmerge_occ_exchange)
foreach(_tk TKXSBase TKSTEP TKIGES)
  find_library(HEXMERGE_OCC_${_tk} ${_tk} HINTS ${OpenCASCADE_LIBRARY_DIR} NO_DEFAULT_PATH)
  if(NOT HEXMERGE_OCC_${_tk} OR NOT EXISTS "${OpenCASCADE_INCLUDE_DIR}/STEPControl_Reader.hxx")
    message(WARNING "OpenCASCADE ${OpenCASCADE_VERSION} found but not its STEP/IGES readers "
                    "(Debian: libocct-data-exchange-dev): hexmerge_occ is not built")
    return()
  endif()
  list(APPEND _hexmerge_occ_exchange ${HEXMERGE_OCC_${_tk}})
endforeach()

add_library(OpenCASCADE::OpenCASCADE INTERFACE IMPORTED GLOBAL)
# OCCT's exported targets carry no include directory.
target_include_directories(OpenCASCADE::OpenCASCADE SYSTEM INTERFACE ${OpenCASCADE_INCLUDE_DIR})
target_link_libraries(OpenCASCADE::OpenCASCADE INTERFACE
  TKernel TKMath TKG2d TKG3d TKGeomBase TKBRep TKGeomAlgo TKTopAlgo TKShHealing TKMesh
  ${_hexmerge_occ_exchange})
message(STATUS "OpenCASCADE ${OpenCASCADE_VERSION}: building hexmerge_occ (the mesher from CAD "
               "and regions by solid)")
