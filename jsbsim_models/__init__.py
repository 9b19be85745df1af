"""silbridge.jsbsim_models"""
