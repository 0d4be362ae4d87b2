"""skyscatter.viewer"""
