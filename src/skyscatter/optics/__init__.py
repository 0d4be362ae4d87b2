"""skyscatter.optics"""
