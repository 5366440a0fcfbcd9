# Writes version.cc with the current git description; run at every build (cmake -P), so outputs never carry a
# stale version. configure_file leaves the file untouched when nothing changed (no needless rebuilds).
set(HOVS_GIT_DESCRIBE "unknown")
if(GIT)
  execute_process(COMMAND ${GIT} describe --always --dirty --tags WORKING_DIRECTORY ${ROOT}
                  OUTPUT_VARIABLE HOVS_GIT_DESCRIBE OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(NOT HOVS_GIT_DESCRIBE)
    set(HOVS_GIT_DESCRIBE "unknown")
  endif()
endif()
configure_file(${SRC} ${DST} @ONLY)
