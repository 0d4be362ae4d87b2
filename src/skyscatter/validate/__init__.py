"""skyscatter.validate"""
