# The interop tests' npm packages (package.json, package-lock.json: exact versions) installed into
# the build tree with `npm ci`, only when the lock file changed since the last install.
# cmake -DNPM=... -DSOURCE=tests/interop -DDEST=build/tests/interop -P npm_ci.cmake
if(NOT NPM OR NOT EXISTS "${NPM}")
  message(FATAL_ERROR "npm not found: run scripts/install-deps.sh (Debian's nodejs and npm)")
endif()
file(MAKE_DIRECTORY "${DEST}")
set(stamp "${DEST}/node_modules/.spotshell-lock")
file(SHA256 "${SOURCE}/package-lock.json" lock)
if(EXISTS "${stamp}")
  file(READ "${stamp}" installed)
  if(installed STREQUAL lock)
    message(STATUS "interop packages up to date in ${DEST}/node_modules")
    return()
  endif()
endif()
configure_file("${SOURCE}/package.json" "${DEST}/package.json" COPYONLY)
configure_file("${SOURCE}/package-lock.json" "${DEST}/package-lock.json" COPYONLY)
# --ignore-scripts: nothing runs at install (the one install script, webgpu's, only acts on macOS).
execute_process(COMMAND "${NPM}" ci --ignore-scripts --no-audit --no-fund
                WORKING_DIRECTORY "${DEST}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "npm ci in ${DEST} failed (${rc}): the npm registry must be reachable")
endif()
file(WRITE "${stamp}" "${lock}")
