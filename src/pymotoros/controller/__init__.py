"""pymotoros.controller"""
