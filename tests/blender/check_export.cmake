# The ctest blender_export_rig: a clip exported from Blender loads with no conversion.
#
#   cmake -DBLENDER=... -DSPOTSHELL=... -DSOURCE=... -DOUT=file.glb -P check_export.cmake
#
# Runs tests/blender/export_rig.py in Blender (glTF Binary, animation on), then `spotshell info`
# on the file: its clip is "bend", it has 3 joints, its frame range is Blender's frames 1 to 25 at
# 24 fps (the add-on writes frame f at f / 24 s: 1/24 to 25/24 s, a 1 s clip), the pose at the
# clip's first frame is the rest pose, and the pose at mid-clip (frame 13, both upper bones turned
# 40 degrees) has the bounds the closed form gives. (A CMake script rather than Python: a Python
# from pyenv or a venv first on PATH would be the one Blender's own Python starts from, without
# its numpy, and the export would fail.)
foreach(v BLENDER SPOTSHELL SOURCE OUT)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "check_export.cmake: -D${v}=... missing")
  endif()
endforeach()
file(REMOVE "${OUT}")
execute_process(COMMAND "${BLENDER}" -b --factory-startup --python-exit-code 1
                        --python "${SOURCE}/tests/blender/export_rig.py" -- "${OUT}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS "${OUT}")
  message(FATAL_ERROR "Blender's export failed (exit ${rc}):\n${out}\n${err}")
endif()

set(failures "")
# `spotshell info --mesh OUT [--time T]`'s output in `var`, and its bounds in var_lo / var_hi
# (lists of three numbers).
function(info var)
  execute_process(COMMAND "${SPOTSHELL}" info --mesh "${OUT}" ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE text ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "spotshell info --mesh ${OUT} ${ARGN} failed (exit ${rc}): ${err}")
  endif()
  message(STATUS "spotshell info ${ARGN}:\n${text}")
  if(NOT text MATCHES "bounds +\\[([^]]*)\\] \\.\\. \\[([^]]*)\\]")
    message(FATAL_ERROR "no bounds in:\n${text}")
  endif()
  string(REPLACE " " ";" lo "${CMAKE_MATCH_1}")
  string(REPLACE " " ";" hi "${CMAKE_MATCH_2}")
  set(${var} "${text}" PARENT_SCOPE)
  set(${var}_lo "${lo}" PARENT_SCOPE)
  set(${var}_hi "${hi}" PARENT_SCOPE)
endfunction()
info(rest)
if(NOT rest MATCHES "clips +bend\n")
  list(APPEND failures "the one clip is not named after the action 'bend'")
endif()
if(NOT rest MATCHES "clip +bend, 1 s from 0\\.04166")
  list(APPEND failures "the clip is not frames 1 to 25 at 24 fps (1/24 s to 25/24 s)")
endif()
if(NOT rest MATCHES "joints +3\n")
  list(APPEND failures "not three joints")
endif()
if(NOT rest MATCHES "triangles +512\n")
  list(APPEND failures "not the tube's 256 quads")
endif()
# Blender's Z-up tube (radius 0.2, z from 0 to 2) is Y-up in glTF. (if() compares numbers as
# doubles; CMake has no float arithmetic.)
list(GET rest_lo 0 lx)
list(GET rest_lo 1 ly)
list(GET rest_hi 0 hx)
list(GET rest_hi 1 hy)
if(NOT (lx GREATER -0.2001 AND lx LESS -0.1999 AND hx GREATER 0.1999 AND hx LESS 0.2001))
  list(APPEND failures "rest bounds in x ${lx} .. ${hx}, not -0.2 .. 0.2")
endif()
if(NOT (ly GREATER -0.0001 AND ly LESS 0.0001 AND hy GREATER 1.9999 AND hy LESS 2.0001))
  list(APPEND failures "rest bounds in y ${ly} .. ${hy}, not 0 .. 2")
endif()
info(first --time 0.0416667)
if(NOT "${first_lo}|${first_hi}" STREQUAL "${rest_lo}|${rest_hi}")
  list(APPEND failures "the pose at the first frame (${first_lo} .. ${first_hi}) is not the rest")
endif()
info(mid --time 0.541667)
list(GET mid_hi 1 mhy)
list(GET mid_hi 2 mhz)
# Both upper bones turned 40 degrees about x (the tip bone 80 degrees in all), by the closed form:
# top y = 0.7 + 0.7 cos 40 + 0.6 cos 80 + 0.2 sin 80 = 1.53738 (the tip's rim), front z =
# 0.7 sin 40 + 0.6 sin 80 + 0.2 cos 80 = 1.07556.
if(NOT (mhy GREATER 1.5364 AND mhy LESS 1.5384))
  list(APPEND failures "mid-clip top ${mhy}, not 1.53738 (the bones turned 40 degrees each)")
endif()
if(NOT (mhz GREATER 1.0746 AND mhz LESS 1.0766))
  list(APPEND failures "mid-clip front ${mhz}, not 1.07556 (the bones turned 40 degrees each)")
endif()
if(failures)
  string(REPLACE ";" "\n  " text "${failures}")
  message(FATAL_ERROR "FAILED:\n  ${text}")
endif()
message(STATUS "blender_export_rig: passed")
