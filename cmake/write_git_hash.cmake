# cmake -DSOURCE_DIR=<repo> -DOUTPUT=<file.cpp> -P write_git_hash.cmake: writes the definition of
# mpmcd::kGitHash (`git describe --always --dirty --abbrev=12`, "unknown" outside a git checkout)
# to OUTPUT, rewriting it only when the text changes (so that an unchanged hash rebuilds nothing).
execute_process(COMMAND git describe --always --dirty --abbrev=12
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE hash OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT hash)
  set(hash "unknown")
endif()
set(text "// Generated at build time by cmake/write_git_hash.cmake; do not edit.\n#include \"mpmcd/version.hpp\"\nnamespace mpmcd {\nconst char* const kGitHash = \"${hash}\";\n}  // namespace mpmcd\n")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT "${old}" STREQUAL "${text}")
  file(WRITE ${OUTPUT} "${text}")
endif()
