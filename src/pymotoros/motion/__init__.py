"""pymotoros.motion"""
