# Fails when docs/reference/plugins.md differs from what the built plugins'
# descriptors generate. Run by the build (target plugin_reference_check).
execute_process(COMMAND ${THERMOSTAMP} plugins --markdown OUTPUT_VARIABLE generated RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "thermostamp plugins --markdown failed (${rc})")
endif()
file(READ ${REFERENCE} current)
if(NOT generated STREQUAL current)
  message(FATAL_ERROR "docs/reference/plugins.md is stale: regenerate it with\n"
                      "  build/bin/thermostamp plugins --markdown > docs/reference/plugins.md")
endif()
