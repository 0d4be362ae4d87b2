"""skyscatter.astro"""
