# LEAKMON_SANITIZE=address,undefined  or  LEAKMON_SANITIZE=thread
if(LEAKMON_SANITIZE)
  add_compile_options(-fsanitize=${LEAKMON_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${LEAKMON_SANITIZE})
  add_compile_definitions(LEAKMON_SANITIZED=1)
endif()
