-- motioncue: send the player aircraft's body-frame g-loads and angular velocity to motioncue.
--
-- Install: copy this file to  Saved Games\DCS\Scripts\MotioncueExport.lua  (DCS.openbeta for
-- the open beta) and add this line to  Saved Games\DCS\Scripts\Export.lua  (create the file if
-- it does not exist):
--
--     dofile(lfs.writedir() .. [[Scripts\MotioncueExport.lua]])
--
-- Then run  motioncue bridge --source dcs ...  (UDP port 20800 on this PC; change host and
-- port below to send to another machine). Export hooks already defined by other tools keep
-- working: this script calls them after its own.
--
-- One text datagram per frame:  MCDCS1 <model time s> <ax> <ay> <az> <wx> <wy> <wz>
-- with LoGetAccelerationUnits() (g, body axes x nose, y up, z right wing; 1 g up in level
-- flight) and LoGetAngularVelocity() (rad/s, same axes). Nothing is sent without an own
-- aircraft (spectator, menus); the model time stands still while the simulation is paused.

local motioncue = { host = "127.0.0.1", port = 20800 }

package.path = package.path .. ";.\\LuaSocket\\?.lua"
package.cpath = package.cpath .. ";.\\LuaSocket\\?.dll"
local socket = require("socket")

local previousStart = LuaExportStart
local previousAfterNextFrame = LuaExportAfterNextFrame
local previousStop = LuaExportStop

LuaExportStart = function()
    motioncue.udp = socket.udp()
    motioncue.udp:settimeout(0)
    motioncue.udp:setpeername(motioncue.host, motioncue.port)
    if previousStart then previousStart() end
end

LuaExportAfterNextFrame = function()
    local a = LoGetAccelerationUnits()
    local w = LoGetAngularVelocity()
    if motioncue.udp and a and w then
        motioncue.udp:send(string.format("MCDCS1 %.4f %.5f %.5f %.5f %.5f %.5f %.5f",
            LoGetModelTime(), a.x, a.y, a.z, w.x, w.y, w.z))
    end
    if previousAfterNextFrame then previousAfterNextFrame() end
end

LuaExportStop = function()
    if motioncue.udp then
        motioncue.udp:close()
        motioncue.udp = nil
    end
    if previousStop then previousStop() end
end
