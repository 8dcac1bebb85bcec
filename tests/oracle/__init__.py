"""An independent extended-precision oracle for springchain's outputs, and a generator of scenes over the
accepted domain (issue 31). ``reference`` never imports springchain; ``scenes`` writes TOML text."""
