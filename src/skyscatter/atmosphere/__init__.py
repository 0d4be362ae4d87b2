"""skyscatter.atmosphere"""
